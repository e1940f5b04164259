//! Declared state coordinates `z = T x`.
//!
//! Each declared coordinate must be a linear function of the states (energy variables, inertia flows `p/I`,
//! integrated flows), without inputs, time or a constant part; [`derive_coords`] checks this when the equations are
//! derived.
//!
//! The state `x` here is the energy state extended by the integrated flows the coordinates (or the dynamics) use,
//! which may be larger than the number of coordinates: the back-support model has 6 energy states and 4 integrated
//! angles, and 7 declared coordinates. The extension is redundant: a spring deflection `q` and the angles `θ` obey
//! `q̇ = Σ c_k θ̇_k`, so `w'x = q - Σ c_k θ_k` is constant along every trajectory. In general the linear invariants
//! are the vectors `w` with `w'[A B] = 0`. Taking them zero (the integrated flows start consistent with the
//! deflections, as for a system at rest at the origin) confines `x` to the invariant subspace `K = {x : W'x = 0}`;
//! with a basis `N` of `K` and `T N` square and invertible, `x = N (T N)⁻¹ z = M z` on `K`, and
//! `A_z = T A M`, `B_z = T B`, `C_z = C M`, `D_z = D`. When `T` is square over the extended state this is the plain
//! similarity `A_z = T A T⁻¹`. Anything else (too few or too many independent coordinates) is an error that says
//! which.

use super::build::{ConvertError, Ctx};
use super::dense::{self, Mat};
use super::linear::{LinearError, NumericStateSpace, StateSelection, numeric_state_space};
use super::resolve::Resolver;
use super::symbols::{self, Sym, SymExt};
use super::{Equations, StateSpec, codes, coord_name};
use crate::diagnostic::Diagnostic;
use crate::ir::{Expr as IrExpr, Model};
use crate::symbolic::Expr;

/// Why the state space in declared coordinates could not be formed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CoordsError {
    #[error("the model declares no coordinates")]
    NoCoords,
    #[error("the declared coordinates could not be derived (see the diagnostics)")]
    Underived,
    #[error(transparent)]
    Linear(#[from] LinearError),
    #[error("coordinate `{coord}` could not be evaluated: {reason}")]
    Eval { coord: String, reason: String },
    #[error(
        "the {coords} declared coordinates do not determine the state: the states they use span {subspace} dimensions \
         (after the {invariants} linear invariants of the integrated flows), so the map is not invertible"
    )]
    NotInvertible {
        coords: usize,
        subspace: usize,
        invariants: usize,
    },
    #[error(
        "the declared coordinates are dependent: T restricted to the reachable state subspace is singular"
    )]
    Singular,
}

/// Converts and checks the declared coordinates; `None` (with diagnostics) when one is not linear in the states.
pub(crate) fn derive_coords(
    model: &Model,
    ctx: &Ctx,
    resolver: &mut Resolver,
    list: &[IrExpr],
    rate_of: &dyn Fn(&Expr) -> Expr,
    states: &[StateSpec],
    diags: &mut Vec<Diagnostic>,
) -> Option<Vec<(String, Expr)>> {
    let mut out = Vec::new();
    let mut ok = true;
    let mut names = super::naming::UniqueNames::default();
    for (k, e) in list.iter().enumerate() {
        let name = names.claim(&coord_name(model, e, k));
        let fail = |msg: String| {
            let d = Diagnostic::error(codes::COORDS, format!("declared coordinate `{name}` {msg}"))
                .with_help("a coordinate must be a linear combination of p(x), q(x), flows of inertias and integrated flows");
            match model.spans.coords.get(k) {
                Some(s) => d.with_primary(*s, "this coordinate"),
                None => d,
            }
        };
        let value = match ctx.convert(e) {
            Ok(v) => v,
            Err(ConvertError::Unsupported(what)) => {
                diags.push(fail(format!("cannot be expressed: {what}")));
                ok = false;
                continue;
            }
        };
        let value = match resolver.expr(&value) {
            Ok(v) => rate_of(&v),
            Err(_) => {
                diags.push(fail(
                    "depends on variables that could not be derived".into(),
                ));
                ok = false;
                continue;
            }
        };
        if let Some(reason) = nonlinear_reason(&value, states) {
            diags.push(fail(reason));
            ok = false;
            continue;
        }
        out.push((name, value));
    }
    ok.then_some(out)
}

/// Why `e` is not a linear function of the states, if it is not.
fn nonlinear_reason(e: &Expr, states: &[StateSpec]) -> Option<String> {
    let mut bad = None;
    e.for_each_sym(&mut |s| {
        if bad.is_none()
            && matches!(
                s,
                Sym::Input(_) | Sym::InputDot(_) | Sym::Time | Sym::StateDot(_)
            )
        {
            bad = Some(s);
        }
    });
    if bad.is_some() {
        return Some("depends on inputs or time".into());
    }
    for (j, state) in states.iter().enumerate() {
        match symbols::diff(e, Sym::State(j)) {
            Ok(d) if d.any_sym(&|s| matches!(s, Sym::State(_))) => {
                return Some(format!("is not linear in `{}`", state.name));
            }
            Ok(_) => {}
            Err(_) => return Some("cannot be differentiated".into()),
        }
    }
    let offset = symbols::subst(e, &mut |s| matches!(s, Sym::State(_)).then(Expr::zero));
    (!offset.is_zero()).then(|| "has a constant part".into())
}

/// The numeric state space in the declared coordinates at parameter values `params`.
pub fn declared_state_space(
    eqs: &Equations,
    params: &[f64],
) -> Result<NumericStateSpace, CoordsError> {
    let coords = eqs.coords.as_ref().ok_or(CoordsError::NoCoords)?;
    if coords.is_empty() {
        return Err(CoordsError::Underived);
    }
    let full = numeric_state_space(eqs, StateSelection::All, params)?;
    let n_all = full.states.len();
    // The states in play: energy states, and the integrated flows that the coordinates, the energy rates or the
    // outputs use (closed under the integrands' own use).
    let mut used = vec![false; n_all];
    used[..eqs.energy_states.min(n_all)]
        .iter_mut()
        .for_each(|u| *u = true);
    for (_, e) in coords {
        e.for_each_sym(&mut |s| {
            if let Sym::State(j) = s
                && let Some(u) = used.get_mut(j)
            {
                *u = true;
            }
        });
    }
    for row in &full.c {
        for (j, v) in row.iter().enumerate() {
            if *v != 0.0 {
                used[j] = true;
            }
        }
    }
    loop {
        let mut changed = false;
        for i in 0..n_all {
            if !used[i] {
                continue;
            }
            for (j, &a_ij) in full.a[i].iter().enumerate() {
                if a_ij != 0.0 && !used[j] {
                    used[j] = true;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    let idx: Vec<usize> = (0..n_all).filter(|&j| used[j]).collect();
    let n = idx.len();
    let pick = |m: &Mat, rows: bool| -> Mat {
        if rows {
            idx.iter()
                .map(|&i| idx.iter().map(|&j| m[i][j]).collect())
                .collect()
        } else {
            m.iter()
                .map(|r| idx.iter().map(|&j| r[j]).collect())
                .collect()
        }
    };
    let a = pick(&full.a, true);
    let b: Mat = idx.iter().map(|&i| full.b[i].clone()).collect();
    let c = pick(&full.c, false);
    // T: coordinate coefficients.
    let value = |s: Sym| match s {
        Sym::Param(i) => params.get(i).copied(),
        _ => None,
    };
    let mut t = dense::zeros(coords.len(), n);
    for (r, (name, e)) in coords.iter().enumerate() {
        for (k, &j) in idx.iter().enumerate() {
            let d = symbols::diff(e, Sym::State(j)).map_err(|_| CoordsError::Eval {
                coord: name.clone(),
                reason: "not differentiable".into(),
            })?;
            t[r][k] = symbols::eval(&d, &value).map_err(|err| CoordsError::Eval {
                coord: name.clone(),
                reason: format!("{err:?}"),
            })?;
        }
        // A coordinate using a state outside the set cannot happen: every state a coordinate uses is in it.
    }
    let m = coords.len();
    let big_m: Mat = if m == n {
        let identity: Mat = (0..n)
            .map(|i| (0..n).map(|j| f64::from(u8::from(i == j))).collect())
            .collect();
        dense::solve(&t, &identity).ok_or(CoordsError::Singular)?
    } else {
        // Linear invariants: w with w'[A B] = 0.
        let ab: Mat = (0..n)
            .map(|i| a[i].iter().chain(b[i].iter()).copied().collect())
            .collect();
        let w = dense::null_space(&dense::transpose(&ab), n);
        let invariants = dense::cols(&w);
        let basis = dense::null_space(&dense::transpose(&w), n);
        let k = if invariants == 0 {
            n
        } else {
            dense::cols(&basis)
        };
        let basis = if invariants == 0 {
            (0..n)
                .map(|i| (0..n).map(|j| f64::from(u8::from(i == j))).collect())
                .collect()
        } else {
            basis
        };
        if k != m {
            return Err(CoordsError::NotInvertible {
                coords: m,
                subspace: k,
                invariants,
            });
        }
        let tn = dense::mul(&t, &basis);
        let identity: Mat = (0..m)
            .map(|i| (0..m).map(|j| f64::from(u8::from(i == j))).collect())
            .collect();
        let inv = dense::solve(&tn, &identity).ok_or(CoordsError::Singular)?;
        dense::mul(&basis, &inv)
    };
    let az = dense::mul(&dense::mul(&t, &a), &big_m);
    let bz = dense::mul(&t, &b);
    let cz = dense::mul(&c, &big_m);
    Ok(NumericStateSpace {
        states: coords.iter().map(|(n, _)| n.clone()).collect(),
        inputs: full.inputs,
        outputs: full.outputs,
        a: az,
        b: bz,
        c: cz,
        d: full.d,
    })
}
