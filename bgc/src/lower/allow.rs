//! `allow CODE NODE "reason";`: a finding the model intends, acknowledged at the element it is located at.
//!
//! The statement resolves `NODE` like `e(NODE)` does (`gear_in`, `g.inertia` for an element of instance `g`) and
//! records an [`Allowance`] in the model's span table; the causality stage then leaves that finding out
//! (`causality::allow`) and warns when an `allow` matches none (`BG0542`), so an acknowledgement cannot outlive the
//! finding it was written for.

use super::builder::Builder;
use crate::diagnostic::Diagnostic;
use crate::ir::{Allowance, Target};
use crate::syntax::ast::AllowDecl;

/// The findings an `allow` may acknowledge: the causality warnings located at one element (derivative causality,
/// an algebraic loop at its first element).
pub const ALLOWABLE: &[&str] = &["BG0510", "BG0520"];

impl Builder<'_> {
    pub(super) fn allow(&mut self, sid: usize, a: &AllowDecl) {
        if !ALLOWABLE.contains(&a.code.name.as_str()) {
            self.diags.push(
                Diagnostic::error("BG0209", format!("`{}` cannot be allowed", a.code.name))
                    .with_primary(a.code.span, "not an acknowledgeable finding")
                    .with_help(format!(
                        "`allow` takes the code of a causality warning located at an element: {}",
                        ALLOWABLE.join(", ")
                    )),
            );
            return;
        }
        match self.reference_target(&a.target, sid) {
            Some((Target::Node(n), ())) => self.model.spans.allowed.push(Allowance {
                code: a.code.name.clone(),
                node: n.index(),
                span: a.span,
            }),
            Some((Target::Bond(_), ())) => self.diags.push(
                Diagnostic::error("BG0209", "`allow` names a bond, not an element")
                    .with_primary(a.target.span, "a bond")
                    .with_help("name the element or junction the finding is located at"),
            ),
            // `reference_target` has reported why the name does not resolve.
            None => {}
        }
    }
}
