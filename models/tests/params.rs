//! The generated `Params`: defaults from the `.bg` file, validation of non-physical values, and the runtime's
//! `Parametric` access by index.

use bgc_models::back_support as m;
use bgc_runtime::model::{ParamError, Parametric};

#[test]
fn defaults_are_those_of_the_file_and_valid() {
    let p = m::Params::default();
    // back_support.bg: J_m = 3.06e-4, r_g = 160, k_eh = 1125.
    assert_eq!(p.J_m, 3.06e-4);
    assert_eq!(p.r_g, 160.0);
    assert_eq!(p.k_eh, 1125.0);
    assert_eq!(p.validate(), Ok(()));
    assert_eq!(m::PARAM_NAMES.len(), m::N_PARAMS);
    assert_eq!(m::PARAM_NAMES[0], "J_m");
    assert_eq!(
        (m::N_STATES, m::N_ENERGY_STATES, m::N_INPUTS, m::N_OUTPUTS),
        (10, 6, 2, 3)
    );
    assert_eq!(m::INPUT_NAMES, ["tau_m", "omega_h"]);
    assert_eq!(m::OUTPUT_NAMES, ["omega_m", "tau_s", "tau_h"]);
}

fn refused(p: m::Params) -> (&'static str, f64) {
    match p.validate() {
        Err(ParamError::NonPhysical { name, value, .. }) => (name, value),
        other => panic!("expected a refusal, got {other:?}"),
    }
}

#[test]
fn non_physical_values_are_refused_with_the_parameter_named() {
    let base = m::Params::default();
    assert_eq!(refused(m::Params { J_m: 0.0, ..base }), ("J_m", 0.0));
    assert_eq!(
        refused(m::Params {
            J_sext: -1e-3,
            ..base
        }),
        ("J_sext", -1e-3)
    );
    // A stiffness enters as the compliance 1/k_g: zero gives an infinite compliance, negative a negative one.
    assert_eq!(refused(m::Params { k_g: 0.0, ..base }), ("k_g", 0.0));
    assert_eq!(refused(m::Params { k_s: -5.0, ..base }), ("k_s", -5.0));
    assert_eq!(refused(m::Params { b_h: -0.1, ..base }), ("b_h", -0.1));
    assert_eq!(refused(m::Params { r_g: 0.0, ..base }), ("r_g", 0.0));
    let (name, value) = refused(m::Params {
        d_g: f64::NAN,
        ..base
    });
    assert_eq!(name, "d_g");
    assert!(value.is_nan());
    assert_eq!(
        refused(m::Params {
            b_g: f64::INFINITY,
            ..base
        })
        .0,
        "b_g"
    );
    // Zero resistances are physical (the paper neglects b_f, d_s and d_eh).
    assert_eq!(
        m::Params {
            b_f: 0.0,
            d_s: 0.0,
            ..base
        }
        .validate(),
        Ok(())
    );
    assert!(m::Model::new(m::Params { J_h: 0.0, ..base }).is_err());
}

#[test]
fn parametric_access_refuses_and_keeps_the_old_value() {
    let mut model = m::Model::default();
    assert_eq!(model.param_names(), &m::PARAM_NAMES);
    assert_eq!(model.param(5), Some(2.64e4));
    assert_eq!(model.set_param(5, 3.0e4), Ok(()));
    assert_eq!(model.params().k_g, 3.0e4);
    assert!(matches!(
        model.set_param(5, -1.0),
        Err(ParamError::NonPhysical { name: "k_g", .. })
    ));
    assert_eq!(model.params().k_g, 3.0e4);
    assert_eq!(
        model.set_param(99, 1.0),
        Err(ParamError::NoSuchParam { index: 99 })
    );
    assert_eq!(model.param(99), None);
}

/// A parameter the equations divide by, with no element check to keep it from zero: the walking leg's Coulomb
/// regularisation `eps` (`tanh(ω/eps)`), the rehabilitation leg's gait period. Before, `validate` accepted 0 and
/// every evaluation gave NaN; now it is refused with its name and the reason.
#[test]
fn a_zero_the_equations_divide_by_is_refused() {
    use bgc_models::{rehab_leg, walking_leg};
    let leg = walking_leg::Params::default();
    assert_eq!(leg.validate(), Ok(()));
    match (walking_leg::Params { eps: 0.0, ..leg }).validate() {
        Err(ParamError::NonPhysical {
            name,
            value,
            reason,
        }) => {
            assert_eq!((name, value), ("eps", 0.0));
            assert_eq!(
                reason,
                "the equations divide by it, and its reciprocal is not finite"
            );
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
    // A subnormal value has no finite reciprocal either.
    let tiny = walking_leg::Params { eps: 1e-310, ..leg };
    assert!(tiny.validate().is_err());
    let rehab = rehab_leg::Params::default();
    assert!(matches!(
        (rehab_leg::Params {
            T_gait: 0.0,
            ..rehab
        })
        .validate(),
        Err(ParamError::NonPhysical { name: "T_gait", .. })
    ));
}
