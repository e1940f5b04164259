//! Outputs, integrated flows (`var`) and declared coordinates, resolved once the graph and its domains are known,
//! and the unused-parameter warning (BG0402), given once every expression has been resolved.
//!
//! An output's declared unit must be the unit of its expression; a var's declared unit must be its integrand's unit
//! times seconds (BG0303). A declaration whose unit could not be read is not checked again.
//!
//! Outputs and integrated flows hold their values in their declared units: `output w [rpm] = f(rotor);` is the
//! rotor speed divided by the rpm's scale, so that the CSV of `bgc simulate`, the C and D of `bgc statespace` and the
//! generated code all give rpm. References to them convert back to SI (see `exprs::to_si`).

use super::builder::Builder;
use super::exprs::{Allow, Cx, Q, from_si};
use super::scope::Entity;
use crate::diagnostic::Diagnostic;
use crate::units::Dim;

impl Builder<'_> {
    /// Outputs, integrated flows and declared coordinates.
    pub fn build_signals(&mut self) {
        for (id, scope, decl) in std::mem::take(&mut self.pending_outputs) {
            let cx = Cx {
                scope,
                allow: Allow::States {
                    outputs_before: Some(id),
                },
                host: None,
                what: "an output",
            };
            let Some((expr, q)) = self.expr(&decl.value, cx) else {
                continue;
            };
            let declared = self.model.outputs[id].unit.dim;
            let unit_ok = !self.bad_units.contains(&Entity::Output(id));
            if unit_ok && !q.fits(declared) {
                let text = self.model.outputs[id].unit_text.clone();
                self.diags.push(
                    Diagnostic::error(
                        "BG0303",
                        format!(
                            "output `{}` is declared [{text}] but its value is in {}",
                            decl.name.name,
                            q.dim()
                        ),
                    )
                    .with_primary(decl.value.span, format!("this is in {}", q.dim()))
                    .with_secondary(decl.unit.span, "declared unit")
                    .with_help("fix the declared unit or the expression"),
                );
            }
            let unit = self.model.outputs[id].unit;
            self.model.outputs[id].value = from_si(expr, unit);
        }
        for (id, scope, decl) in std::mem::take(&mut self.pending_vars) {
            let cx = Cx {
                scope,
                allow: Allow::States {
                    outputs_before: None,
                },
                host: None,
                what: "an integrated flow",
            };
            let Some((expr, q)) = self.expr(&decl.integrand, cx) else {
                continue;
            };
            let declared = self.model.vars[id].unit.dim;
            let second = Dim::new(0, 0, 1, 0, 0, 0, 0);
            let integral = match q {
                Q::Free => Q::Free,
                Q::Dim(d) => d.checked_mul(second).map(Q::Dim).unwrap_or(Q::Free),
            };
            let unit_ok = !self.bad_units.contains(&Entity::Var(id));
            if unit_ok && !integral.fits(declared) {
                let text = self.model.vars[id].unit_text.clone();
                self.diags.push(
                    Diagnostic::error(
                        "BG0303",
                        format!(
                            "`{}` is declared [{text}] but the integral of its flow is in {}",
                            decl.name.name,
                            integral.dim()
                        ),
                    )
                    .with_primary(
                        decl.integrand.span,
                        format!("this is in {}, its integral in {}", q.dim(), integral.dim()),
                    )
                    .with_secondary(decl.unit.span, "declared unit")
                    .with_help("the unit of `int(x)` is the unit of `x` times seconds"),
                );
            }
            let unit = self.model.vars[id].unit;
            self.model.vars[id].integrand = from_si(expr, unit);
        }
        if let Some((scope, decl)) = self.pending_coords.take() {
            let cx = Cx {
                scope,
                allow: Allow::States {
                    outputs_before: None,
                },
                host: None,
                what: "a state coordinate",
            };
            let mut coords = Vec::new();
            for c in &decl.coords {
                if let Some((expr, _)) = self.expr(c, cx) {
                    coords.push(expr);
                    self.model.spans.coords.push(c.span);
                }
            }
            self.model.coords = Some(coords);
        }
    }

    /// BG0402 for every parameter nothing uses (none while an unknown name without a close match is reported).
    pub fn unused_params(&mut self) {
        if self.unmatched_name {
            return;
        }
        for (p, info) in self.model.params.iter().zip(&self.params) {
            if !info.used {
                self.diags.push(
                    Diagnostic::warning("BG0402", format!("parameter `{}` is never used", p.name))
                        .with_primary(info.name_span, "declared here")
                        .with_help("remove it, or use it in an element, law or output"),
                );
            }
        }
    }
}
