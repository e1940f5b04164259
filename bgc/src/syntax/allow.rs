//! `allow CODE NODE "reason";`: the acknowledgement of an intended finding (see `lower::allow` for its meaning).

use super::ast::AllowDecl;
use super::parser::{PResult, Parser};

impl Parser<'_> {
    /// `allow BG0510 gear_in "why";` (the `allow` keyword is next).
    pub(super) fn allow(&mut self) -> PResult<AllowDecl> {
        let start = self.peek().start;
        self.bump();
        let code = self.expect_name("a diagnostic code such as `BG0510`")?;
        let target = self.node_ref()?;
        let reason = self.description();
        self.expect_semi("the `allow` statement")?;
        Ok(AllowDecl {
            code,
            target,
            reason,
            span: self.span_from(start),
        })
    }
}
