//! Bond statements and the checks of their shape.

use super::ast::*;
use super::lexer::Tok;
use super::parser::{PResult, Parser};
use crate::diagnostic::Diagnostic;

impl Parser<'_> {
    /// `bond [LABEL:] a -> b -> c, d [stroke[!] NODE];`
    pub(super) fn bond(&mut self) -> PResult<BondStmt> {
        let start = self.bump().start;
        let mut label = None;
        if self.peek().kind == Tok::Ident && self.nth(1).kind == Tok::Colon {
            label = Some(self.expect_name("the bond's name")?);
            self.bump();
        }
        // Most bonds are `a -> b`: room for two groups saves a reallocation per bond.
        let mut chain = Vec::with_capacity(2);
        chain.push(self.node_group()?);
        if !self.at(Tok::Arrow) {
            return Err(self.expected(
                "`->`",
                "a bond joins two nodes: `bond a -> b;` (power flows from a to b)",
            ));
        }
        while self.eat(Tok::Arrow).is_some() {
            chain.push(self.node_group()?);
        }
        let mut hint = None;
        if self.at_word("stroke") {
            let kw = self.bump();
            let fixed = self.eat(Tok::Bang).is_some();
            let at = self.node_ref()?;
            hint = Some(CausalHint {
                at,
                fixed,
                span: self.span_from(kw.start),
            });
        }
        self.expect_semi("the bond")?;
        let mut bond = BondStmt {
            label,
            chain,
            hint,
            malformed: false,
            span: self.span_from(start),
        };
        bond.malformed = self.check_bond_shape(&bond);
        Ok(bond)
    }

    /// One node or a comma-separated fan-out.
    fn node_group(&mut self) -> PResult<ShortList<NodeRef>> {
        let mut group = ShortList::one(self.node_ref()?);
        while self.eat(Tok::Comma).is_some() {
            group.push(self.node_ref()?);
        }
        Ok(group)
    }

    /// Fan-outs only at the end; labels and hints only on single bonds; a hint at one of the bond's ends. Whether
    /// a fan-out comes before the end (the statement is then malformed).
    fn check_bond_shape(&mut self, bond: &BondStmt) -> bool {
        let last = bond.chain.len().saturating_sub(1);
        let mut malformed = false;
        for group in bond.chain.iter().take(last) {
            if let (Some(first), Some(end)) = (group.first(), group.last())
                && group.len() > 1
            {
                malformed = true;
                self.diags.push(
                    Diagnostic::error("BG0110", "a fan-out must end the chain")
                        .with_primary(first.span.to(end.span), "this fan-out is followed by `->`")
                        .with_help("split the statement: `bond a -> b, c;` then one `bond` per continuing chain"),
                );
            }
        }
        let single = bond.chain.len() == 2 && bond.chain.iter().all(|g| g.len() == 1);
        if single {
            if let Some(h) = &bond.hint {
                let ends: Vec<&NodeRef> = bond.chain.iter().flatten().collect();
                if !ends.iter().any(|n| same_node(n, &h.at)) {
                    let mut d = Diagnostic::error(
                        "BG0113",
                        "the causal stroke must be at one of the bond's ends",
                    )
                    .with_primary(h.at.span, "not an end of this bond");
                    for n in ends {
                        d = d.with_secondary(n.span, "an end of the bond");
                    }
                    self.diags.push(
                        d.with_help("name one of the two nodes the bond joins after `stroke`"),
                    );
                }
            }
            return malformed;
        }
        let what = if bond.chain.len() > 2 {
            "a chain"
        } else {
            "a fan-out"
        };
        let whole = bond
            .chain
            .first()
            .and_then(|g| g.first())
            .zip(bond.chain.last().and_then(|g| g.last()))
            .map(|(a, b)| a.span.to(b.span));
        if let Some(label) = &bond.label {
            let mut d =
                Diagnostic::error("BG0110", format!("a bond name cannot be given to {what}"))
                    .with_primary(label.span, "this names several bonds");
            if let Some(w) = whole {
                d = d.with_secondary(w, format!("{what} of several bonds"));
            }
            self.diags
                .push(d.with_help("name a single bond: write it as its own `bond NAME: a -> b;`"));
            // The name is declared by nothing now: a reference to it is not reported again as unknown.
            self.unparsed.names.push(label.clone());
        }
        if let Some(h) = &bond.hint {
            let mut d = Diagnostic::error(
                "BG0110",
                format!("a causality hint cannot be given to {what}"),
            )
            .with_primary(h.span, "this hint would apply to several bonds");
            if let Some(w) = whole {
                d = d.with_secondary(w, format!("{what} of several bonds"));
            }
            self.diags
                .push(d.with_help("give the hint on a single bond: `bond a -> b stroke b;`"));
        }
        malformed
    }
}

/// Two node references name the same node (their spans aside).
fn same_node(a: &NodeRef, b: &NodeRef) -> bool {
    a.port.map(|p| p.0) == b.port.map(|p| p.0)
        && a.path.len() == b.path.len()
        && a.path.iter().zip(&b.path).all(|(x, y)| x.name == y.name)
}
