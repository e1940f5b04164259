//! The modules generated without the runtime compute, to the bit, what the models crate's modules (generated with
//! it) compute: rhs, outputs, Jacobians and energy at random states and inputs, and the same parameter checks with
//! the same messages.

use bgc_models::corpus;

/// A small deterministic generator (xorshift64*), uniform in `[lo, hi)`.
struct Rng(u64);

impl Rng {
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let r = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d);
        lo + (hi - lo) * ((r >> 11) as f64 / (1u64 << 53) as f64)
    }
}

fn bits(values: &[f64]) -> Vec<u64> {
    values.iter().map(|v| v.to_bits()).collect()
}

macro_rules! same {
    ($($test:ident: $no_std:path, $with:path);* $(;)?) => {
        $(
            #[test]
            fn $test() {
                use $no_std as a;
                use $with as b;
                assert_eq!(a::STATE_NAMES, b::STATE_NAMES);
                assert_eq!(a::PARAM_NAMES, b::PARAM_NAMES);
                let pa = a::Params::default();
                let pb = b::Params::default();
                let values: Vec<f64> = (0..a::N_PARAMS).filter_map(|i| pa.get(i)).collect();
                assert_eq!(values, (0..b::N_PARAMS).filter_map(|i| pb.get(i)).collect::<Vec<_>>());
                let mut rng = Rng(17);
                let mut checked = 0;
                for _ in 0..50 {
                    let x = a::State::from_fn(|_, _| rng.uniform(-1.0, 1.0));
                    let u = a::Inputs::from_fn(|_, _| rng.uniform(-1.0, 1.0));
                    let t = rng.uniform(0.0, 2.0);
                    let xb = b::State::from_column_slice(x.as_slice());
                    let ub = b::Inputs::from_column_slice(u.as_slice());
                    let (mut da, mut db) = (a::State::zeros(), b::State::zeros());
                    a::rhs_into(&pa, t, &x, &u, &mut da);
                    b::rhs_into(&pb, t, &xb, &ub, &mut db);
                    assert_eq!(bits(da.as_slice()), bits(db.as_slice()));
                    let (ya, yb) = (a::outputs(&pa, t, &x, &u), b::outputs(&pb, t, &xb, &ub));
                    assert_eq!(bits(ya.as_slice()), bits(yb.as_slice()));
                    let (mut ja, mut jb) = (a::JacX::zeros(), b::JacX::zeros());
                    a::jac_x_into(&pa, t, &x, &u, &mut ja);
                    b::jac_x_into(&pb, t, &xb, &ub, &mut jb);
                    assert_eq!(bits(ja.as_slice()), bits(jb.as_slice()));
                    let (mut ka, mut kb) = (a::OutJacU::zeros(), b::OutJacU::zeros());
                    a::output_jac_u_into(&pa, t, &x, &u, &mut ka);
                    b::output_jac_u_into(&pb, t, &xb, &ub, &mut kb);
                    assert_eq!(bits(ka.as_slice()), bits(kb.as_slice()));
                    let ea = a::stored_energy(&pa, t, &x, &u);
                    assert_eq!(ea.to_bits(), b::stored_energy(&pb, t, &xb, &ub).to_bits());
                    checked += usize::from(da.iter().all(|v| v.is_finite()));
                }
                assert!(checked > 0, "no finite rate was compared");
                // A non-physical value is refused alike, with the same message.
                let (mut qa, mut qb) = (pa, pb);
                let ra = qa.set(0, -1.0).map_err(|e| e.to_string());
                let rb = qb.set(0, -1.0).map_err(|e| e.to_string());
                assert_eq!(ra, rb);
                let nan_a = qa.set(0, f64::NAN).map_err(|e| e.to_string());
                assert_eq!(nan_a, qb.set(0, f64::NAN).map_err(|e| e.to_string()));
                assert!(nan_a.is_err_and(|m| m.contains("not a finite number")));
                assert_eq!(
                    qa.set(99, 1.0).map_err(|e| e.to_string()),
                    Err("no parameter with index 99".to_string())
                );
            }
        )*
    };
}

same! {
    back_support: bgc_no_std_check::back_support, bgc_models::back_support;
    pendulum_rig: bgc_no_std_check::pendulum_rig, bgc_models::pendulum_rig;
    rehab_leg: bgc_no_std_check::rehab_leg, bgc_models::rehab_leg;
    walking_leg: bgc_no_std_check::walking_leg, bgc_models::walking_leg;
    pendulum: bgc_no_std_check::pendulum, corpus::pendulum;
}
