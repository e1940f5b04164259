//! `jac_x_sparse_into`: `∂f/∂x` of a large model as triplets, without the `N_STATES × N_STATES` matrix a `JacX`
//! takes on the stack.
//!
//! The entries are listed column by column (`JAC_X_ROWS`, `JAC_X_COLS`) and computed in parts of bounded size. The
//! rows of a mass block (an I-field, inertias coupled through a varying modulus) hold the generalised forces `F` of
//! `M(q) ẋ_B = F`; they are listed in every column where `∂F` or `M` has an entry, written as `∂F` first, and then
//! turned into the rates' entries block by block, `M⁻¹ (∂F − (∂M/∂x_c) ẋ_B)`, by private functions of a bounded
//! number of blocks each. Models with algebraic loops keep only the dense `jac_x_into` (the loops' correction
//! writes to the matrix as a whole).

use super::super::mass::MassPlan;
use super::functions::entry_label;
use super::parts::{MAX_PART_STATEMENTS, Out, Statement};
use super::{Arg, Function, Writer};
use crate::equations::SparseMatrix;
use crate::symbolic::Expr;
use std::collections::HashMap;

/// One mass block's rows in the triplets: the block and the columns of its rows, increasing.
struct BlockColumns<'p> {
    block: &'p MassPlan,
    columns: Vec<usize>,
}

impl Writer<'_> {
    /// Whether `∂f/∂x` also gets its sparse form: when a `JacX` takes more than
    /// [`super::model::MAX_CONSTANT_JACOBIAN_BYTES`] (a thread's stack holds few of them) and every entry is an
    /// expression of its own or a mass block's (no loop correction writes to the matrix as a whole).
    pub(super) fn wants_sparse_jac_x(&self) -> bool {
        !super::model::square_fits(self.plan.states.len())
            && self.shared_lets("jac_x_into").is_empty()
            && self.plan.loops.is_none()
    }

    /// `JAC_X_NNZ`, `JAC_X_ROWS`, `JAC_X_COLS` and `jac_x_sparse_into`: the entries of `∂f/∂x` that are not
    /// identically zero, column by column, without an `N_STATES × N_STATES` matrix.
    pub(super) fn sparse_jac_x(
        &mut self,
        m: &SparseMatrix,
        rows: &[String],
        cols: &[String],
        row_prefix: &str,
    ) {
        let plan = self.plan;
        let blocks = block_columns(&plan.mass, m, cols.len());
        let zero = Expr::zero();
        let mut entries: Vec<(usize, usize, &Expr)> =
            m.iter().filter(|(_, c, _)| *c < cols.len()).collect();
        let written: std::collections::HashSet<(usize, usize)> =
            entries.iter().map(|&(r, c, _)| (r, c)).collect();
        for b in &blocks {
            for &r in &b.block.rows {
                for &c in &b.columns {
                    if !written.contains(&(r, c)) {
                        entries.push((r, c, &zero));
                    }
                }
            }
        }
        // Column by column.
        entries.sort_by_key(|&(r, c, _)| (c, r));
        let position: HashMap<(usize, usize), usize> = entries
            .iter()
            .enumerate()
            .map(|(k, &(r, c, _))| ((r, c), k))
            .collect();
        self.triplet_consts(&entries);
        let statements: Vec<Statement> = entries
            .iter()
            .enumerate()
            .map(|(k, &(r, c, e))| Statement {
                label: entry_label((rows, cols, row_prefix), r, c),
                expr: e,
                head: format!("values[{k}] = "),
                tail: ";",
            })
            .collect();
        let mut d = if self.splits(statements.len()) {
            let out = Out {
                name: "values",
                ty: "&mut [f64; JAC_X_NNZ]",
                passed: "values",
            };
            self.parts("jac_x_sparse", &statements, out, false, Vec::new())
        } else {
            let exprs: Vec<&Expr> = entries.iter().map(|e| e.2).collect();
            let mut d = self.draft(&exprs);
            for s in &statements {
                self.statement(&mut d, &s.label, s.expr, &s.head, s.tail);
            }
            d
        };
        if !blocks.is_empty() {
            d.lines.extend(self.comment_lines(
                "The rows of the mass blocks hold ∂F so far: M (∂ẋ_B) = ∂F − (∂M/∂x_c) ẋ_B, solved with each \
                 block's M.",
            ));
            // The rates `ẋ_B` enter through the derivatives of `M` only: constant mass matrices need none.
            let rates = blocks.iter().any(|b| !b.block.derivatives.is_empty());
            if rates {
                d.lines.push("    let mut dx = State::zeros();".into());
                d.lines.push("    rhs_into(p, t, x, u, &mut dx);".into());
                d.uses.t = true;
                d.uses.u = true;
            }
            let passed = if rates {
                "p, x, &dx, values"
            } else {
                "p, x, values"
            };
            for (k, chunk) in blocks.chunks(BLOCKS_PER_PART).enumerate() {
                let name = format!("jac_x_sparse_mass_{}", k + 1);
                d.lines.push(format!("    {name}({passed});"));
                self.mass_part(&name, chunk, &position, rates);
            }
            d.uses.p = true;
            d.uses.x = true;
        }
        let mut args = Self::model_args(d.uses);
        args.push(Arg::new(
            "values",
            "&mut [f64; JAC_X_NNZ]",
            !entries.is_empty(),
        ));
        self.function(Function {
            doc: "Writes the entries of `∂f/∂x` that are not identically zero into `values`, at the rows \
                  `JAC_X_ROWS` and columns `JAC_X_COLS`: the Jacobian of a large model without the \
                  `N_STATES × N_STATES` matrix a `JacX` takes on the stack."
                .to_string(),
            name: "jac_x_sparse_into".to_string(),
            args,
            ret: String::new(),
            body: Self::body_text(&d.lines),
            locals: d.locals,
            inline: false,
        });
    }

    /// `JAC_X_NNZ`, `JAC_X_ROWS` and `JAC_X_COLS` of the entries.
    fn triplet_consts(&mut self, entries: &[(usize, usize, &Expr)]) {
        self.out.push('\n');
        self.doc(
            0,
            "The number of entries of `∂f/∂x` that are not identically zero.",
        );
        self.out.push_str(&format!(
            "pub const JAC_X_NNZ: usize = {};\n",
            entries.len()
        ));
        for (konst, what, pick) in [("JAC_X_ROWS", "row", 0usize), ("JAC_X_COLS", "column", 1)] {
            let list: Vec<String> = entries
                .iter()
                .map(|&(r, c, _)| if pick == 0 { r } else { c }.to_string())
                .collect();
            self.out.push('\n');
            self.doc(
                0,
                &format!("The {what} of each entry of `jac_x_sparse_into`."),
            );
            let head = format!("pub const {konst}: [usize; JAC_X_NNZ] = ");
            self.out.push_str(&super::super::format::array(
                &head, &list, ";", 0, self.width,
            ));
            self.out.push('\n');
        }
    }

    /// A private function that solves the rows of `chunk`'s blocks in `values`, with the rates `dx` at the point
    /// when `rates` (some block's `M` varies).
    fn mass_part(
        &mut self,
        name: &str,
        chunk: &[BlockColumns<'_>],
        position: &HashMap<(usize, usize), usize>,
        rates: bool,
    ) {
        let slopes: Vec<&Expr> = chunk
            .iter()
            .flat_map(|b| b.block.derivatives.iter())
            .flat_map(|(_, dm)| dm.iter().flatten())
            .filter(|e| !e.is_zero())
            .collect();
        let mut d = self.draft(&slopes);
        for b in chunk {
            let (block, n, width) = (b.block, b.block.rows.len(), b.columns.len());
            d.lines.extend(self.comment_lines(&format!(
                "The rows of the mass block of `{}`.",
                super::super::names::comment(&block.element)
            )));
            d.lines.push(format!(
                "    let mut rows = SMatrix::<f64, {n}, {width}>::zeros();"
            ));
            let at = |r: usize, c: usize| position.get(&(r, c)).copied().unwrap_or_default();
            for (i, &r) in block.rows.iter().enumerate() {
                for (k, &c) in b.columns.iter().enumerate() {
                    d.lines
                        .push(format!("    rows[({i}, {k})] = values[{}];", at(r, c)));
                }
            }
            for (c, dm) in &block.derivatives {
                let k = b.columns.binary_search(c).unwrap_or_default();
                let by = self.plan.states.get(*c).map_or("", |s| s.name());
                let cell = |i: usize| format!("rows[({i}, {k})]");
                self.slope_correction(&mut d, (&block.rows, &cell), dm, by);
            }
            d.lines.push(format!(
                "    let solved = bgc_solve(mass_{}(p, x), rows);",
                block.ident
            ));
            for (i, &r) in block.rows.iter().enumerate() {
                for (k, &c) in b.columns.iter().enumerate() {
                    d.lines
                        .push(format!("    values[{}] = solved[({i}, {k})];", at(r, c)));
                }
            }
        }
        let mut args = vec![
            Arg::new("p", "&Params", true),
            Arg::new("x", "&State", true),
        ];
        if rates {
            let reads = chunk.iter().any(|b| !b.block.derivatives.is_empty());
            args.push(Arg::new("dx", "&State", reads));
        }
        args.push(Arg::new("values", "&mut [f64; JAC_X_NNZ]", true));
        let doc =
            format!("The rows of mass blocks of `jac_x_sparse_into` (see `{name}`'s caller).");
        self.private_part(doc, name.to_string(), args, d);
    }
}

/// Blocks per private function: each costs a few statements per entry of its rows.
const BLOCKS_PER_PART: usize = MAX_PART_STATEMENTS / 8;

/// Each block with the columns of its rows: where `∂F` (in `m`) or `M` has an entry.
fn block_columns<'p>(blocks: &'p [MassPlan], m: &SparseMatrix, n: usize) -> Vec<BlockColumns<'p>> {
    let mut block_of: HashMap<usize, usize> = HashMap::new();
    for (k, b) in blocks.iter().enumerate() {
        for &r in &b.rows {
            block_of.insert(r, k);
        }
    }
    let mut columns: Vec<Vec<usize>> = blocks
        .iter()
        .map(|b| b.derivatives.iter().map(|(c, _)| *c).collect())
        .collect();
    for (r, c, _) in m.iter().filter(|(_, c, _)| *c < n) {
        if let Some(&k) = block_of.get(&r) {
            columns[k].push(c);
        }
    }
    blocks
        .iter()
        .zip(columns)
        .map(|(block, mut columns)| {
            columns.sort_unstable();
            columns.dedup();
            BlockColumns { block, columns }
        })
        .collect()
}
