//! Hints for a unit mismatch (BG0303) that the domain explains: a value that has exactly the unit its element needs
//! in another domain almost always means the domain was not declared (`domain electrical;` forgotten, so the
//! bonds took the model's default), not that the value is wrong.

use super::builder::Builder;
use crate::ir::Domain;
use crate::syntax::ast::ElementKind;
use crate::units::{Dim, domain_units, storage_parameter_unit};

/// The place of a value whose unit depends on its element's domain.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Place {
    /// The value of a source or the parameter of a C, I or R, on one port.
    OnePort(ElementKind),
    /// The modulus of a TF, GY, MTF or MGY, from its input port to its output port.
    TwoPort(ElementKind),
}

/// The domains (one, or input and output for a two-port) in which a value in `found` fits `place`, other than
/// `current`.
pub(crate) fn fitting_domains(
    place: Place,
    found: Dim,
    current: (Domain, Domain),
) -> Vec<(Domain, Domain)> {
    let mut out = Vec::new();
    for din in Domain::ALL {
        for dout in Domain::ALL {
            let fits = match place {
                Place::OnePort(kind) => din == dout && one_port_unit(kind, din) == Some(found),
                Place::TwoPort(kind) => two_port_unit(kind, din, dout) == Some(found),
            };
            if fits && (din, dout) != current {
                out.push((din, dout));
            }
        }
    }
    out
}

fn one_port_unit(kind: ElementKind, d: Domain) -> Option<Dim> {
    use ElementKind as K;
    let u = domain_units(d);
    match kind {
        K::Se | K::MSe => Some(u.effort),
        K::Sf | K::MSf => Some(u.flow),
        _ => storage_parameter_unit(kind, d).map(|(dim, _)| dim),
    }
}

fn two_port_unit(kind: ElementKind, din: Domain, dout: Domain) -> Option<Dim> {
    let (ui, uo) = (domain_units(din), domain_units(dout));
    let num = if matches!(kind, ElementKind::TF | ElementKind::MTF) {
        ui.flow
    } else {
        ui.effort
    };
    num.checked_div(uo.flow)
}

impl Builder<'_> {
    /// Adds to the last diagnostic (a BG0303 about `name`) a note naming the domain in which its value fits and
    /// where to declare it.
    pub(crate) fn suggest_domain(
        &mut self,
        place: Place,
        name: &str,
        found: Dim,
        current: (Domain, Domain),
    ) {
        let mut fits = fitting_domains(place, found, current);
        // Power usually enters a motor or a pump on its electrical or hydraulic side: a different input domain is the
        // likelier reading.
        fits.sort_by_key(|(din, _)| *din == current.0);
        // A dimensionless value fits every transformer; only a unique, informative match is worth saying.
        let Some(&(din, dout)) = fits.first() else {
            return;
        };
        if found.is_dimensionless() {
            return;
        }
        let note = match place {
            Place::OnePort(_) => format!(
                "{found} is what `{name}` needs in the {} domain, but its bond is {}",
                din.name(),
                current.0.name()
            ),
            Place::TwoPort(_) => {
                let alternatives: Vec<String> = fits
                    .iter()
                    .map(|(a, b)| format!("{} to {}", a.name(), b.name()))
                    .collect();
                format!(
                    "{found} is what `{name}` needs from the {} domain (it is {} to {} now)",
                    alternatives.join(", or from the "),
                    current.0.name(),
                    current.1.name()
                )
            }
        };
        let (d, example) = match place {
            Place::OnePort(kind) => (
                din,
                format!("`{} {name}: {} ...`", kind.keyword(), din.name()),
            ),
            Place::TwoPort(_) if din != current.0 => {
                (din, format!("an element on the input side of `{name}`"))
            }
            Place::TwoPort(_) => (dout, format!("an element on the output side of `{name}`")),
        };
        let help = if self.suggested_domains.contains(&d) {
            format!("the same missing {} domain as above", d.name())
        } else {
            self.suggested_domains.push(d);
            format!(
                "give the {d} part of the model its domain: `: {d}` after the name of one of its elements \
                 ({example}) spreads along its bonds; or `domain {d};` if the whole model is {d}",
                d = d.name()
            )
        };
        if let Some(last) = self.diags.last_mut() {
            last.notes.push(note);
            last.help = Some(help);
        }
    }
}
