//! The energy terms of derived equations at a point, and the power balance they must obey along the motion.

use bgc::equations::symbols::{self as sym, Sym};
use bgc::equations::{EnergyKind, Equations, solve_all};

/// The total energy term of `kind` at `(x, u, t)`, the inputs held (`u̇ = 0`) and the loops solved there; `None`
/// when a term has no closed form or does not evaluate.
pub fn energy_total(
    eqs: &Equations,
    params: &[f64],
    kind: EnergyKind,
    (x, u, t): (&[f64], &[f64], f64),
) -> Option<f64> {
    let known = |s: Sym| match s {
        Sym::Param(i) => params.get(i).copied(),
        Sym::State(i) => x.get(i).copied(),
        Sym::Input(i) => u.get(i).copied(),
        Sym::InputDot(_) => Some(0.0),
        Sym::Time => Some(t),
        _ => None,
    };
    let tears = solve_all(eqs, &known).ok()?;
    let value = |s: Sym| {
        let torn = tears.iter().find(|(z, _)| *z == s);
        torn.map(|(_, v)| *v).or_else(|| known(s))
    };
    let terms = eqs.energy.iter().filter(|term| term.kind == kind);
    terms
        .map(|term| sym::eval(term.value.as_ref()?, &value).ok())
        .sum()
}

/// Whether the energy terms obey the power balance at `(x, u, t)`: the rate of the stored energy along the motion
/// (a central difference along `ẋ`, a step of at most 1e-6 in any state) equals the supplied minus the dissipated
/// power, to 1e-6 of the powers' size. `None` when the rates or a term do not evaluate there.
pub fn power_balance(
    eqs: &Equations,
    params: &[f64],
    (x, u, t): (&[f64], &[f64], f64),
) -> Option<Result<(), String>> {
    let rates = eqs.rates_at(params, x, u, t).ok()?;
    let fastest = rates.iter().fold(0.0f64, |m, r| m.max(r.abs()));
    let h = 1e-6 / (1.0 + fastest);
    let along = |sign: f64| -> Vec<f64> {
        x.iter()
            .zip(&rates)
            .map(|(a, r)| a + sign * h * r)
            .collect()
    };
    let at = |kind, x: &[f64]| energy_total(eqs, params, kind, (x, u, t));
    let ahead = at(EnergyKind::Stored, &along(1.0))?;
    let behind = at(EnergyKind::Stored, &along(-1.0))?;
    let supplied = at(EnergyKind::Supplied, x)?;
    let dissipated = at(EnergyKind::Dissipated, x)?;
    let stored_rate = (ahead - behind) / (2.0 * h);
    let size = 1.0 + supplied.abs() + dissipated.abs() + stored_rate.abs();
    if (stored_rate - (supplied - dissipated)).abs() > 1e-6 * size {
        return Some(Err(format!(
            "d/dt stored {stored_rate}, supplied {supplied}, dissipated {dissipated} at x = {x:?}"
        )));
    }
    Some(Ok(()))
}
