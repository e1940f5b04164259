//! How the tear variables of nonlinear algebraic loops move with the states: the correction that the rates'
//! Jacobian needs when the rates read tears.
//!
//! Block `b` solves `r_b(x, z_b, z_<b) = 0` for its tears `z_b` (earlier blocks' tears `z_<b` are known by then), so
//! by the implicit function theorem
//!
//! ```text
//! ∂z_b/∂x = −(∂r_b/∂z_b)⁻¹ (∂r_b/∂x + Σ_j ∂r_b/∂z_j ∂z_j/∂x)     (j: the earlier tears r_b reads)
//! ∂ẋ_i/∂x = ∂f_i/∂x + Σ_k ∂f_i/∂z_k ∂z_k/∂x
//! ```
//!
//! `∂z_b/∂x` has entries only in the states its residuals read, directly or through the earlier tears they read
//! (the block's columns), so a model of many separate loops keeps a sparse Jacobian: before, any loop made the
//! simulator take finite differences of the whole rhs, one column at a time, and factorise densely.

use super::SimError;
use super::program::{ProgramSeq, Values};
use crate::equations::TearBlock;
use crate::equations::dense::{self, Mat};
use crate::equations::symbols::{self, Sym, SymExt};
use crate::symbolic::Expr;
use std::collections::HashMap;

/// The derivatives of one block's residuals, compiled into one program: the residuals share most of their
/// nodes (a loop's exponential, say), computed once.
#[derive(Clone, Debug)]
struct BlockDerivatives {
    /// The global indices of its tears.
    tears: Vec<usize>,
    /// The states its tears depend on, increasing.
    columns: Vec<usize>,
    /// Per residual: the column positions of its derivatives by states, then the global tears of its derivatives
    /// by tears (its own and earlier blocks'), in the order `program` gives their values.
    by_state: Vec<Vec<usize>>,
    by_tear: Vec<Vec<usize>>,
    program: ProgramSeq,
}

/// The loops' derivatives, compiled: `∂z/∂x` at a point for every tear.
#[derive(Clone, Debug)]
pub(super) struct LoopCorrection {
    blocks: Vec<BlockDerivatives>,
    /// Per global tear: its block and its row there.
    tear_at: Vec<(usize, usize)>,
}

/// `∂z/∂x` at a point, per block: a row per tear over the block's columns (NaN where `∂r_b/∂z_b` is singular).
pub(super) struct TearSlopes(Vec<Mat>);

impl LoopCorrection {
    /// The loops' derivatives over the `n` model states; `None` when a residual uses a function without a
    /// derivative.
    pub(super) fn new(
        loops: &[TearBlock],
        n: usize,
        all: &Tears,
        compile: CompileSeq<'_>,
    ) -> Option<LoopCorrection> {
        let mut blocks: Vec<BlockDerivatives> = Vec::with_capacity(loops.len());
        let mut tear_at = vec![(0, 0); all.len()];
        for (b, block) in loops.iter().enumerate() {
            let tears: Vec<usize> = block
                .tears
                .iter()
                .map(|z| all.index.get(z).copied())
                .collect::<Option<_>>()?;
            for (row, &k) in tears.iter().enumerate() {
                *tear_at.get_mut(k)? = (b, row);
            }
            let mut exprs = Vec::new();
            let mut state_rows = Vec::with_capacity(block.residuals.len());
            let mut by_tear = Vec::with_capacity(block.residuals.len());
            let mut columns: Vec<usize> = Vec::new();
            for r in &block.residuals {
                let (states, tears_read) = all.partition(r, n);
                let (ds, dz) = all.derivatives(r, (&states, &tears_read))?;
                columns.extend(ds.iter().map(|(c, _)| *c));
                // The earlier tears' columns are this block's too.
                for (k, _) in &dz {
                    let (owner, _) = *tear_at.get(*k)?;
                    if owner < b {
                        columns.extend(blocks.get(owner)?.columns.iter().copied());
                    }
                }
                state_rows.push(ds.iter().map(|(c, _)| *c).collect::<Vec<_>>());
                by_tear.push(dz.iter().map(|(k, _)| *k).collect());
                exprs.extend(ds.into_iter().chain(dz).map(|(_, d)| d));
            }
            columns.sort_unstable();
            columns.dedup();
            let position = |c: usize| columns.binary_search(&c).ok();
            let by_state = state_rows
                .into_iter()
                .map(|row| row.into_iter().map(position).collect::<Option<Vec<_>>>())
                .collect::<Option<Vec<_>>>()?;
            let program = compile(&exprs, "an algebraic loop's derivative").ok()?;
            blocks.push(BlockDerivatives {
                tears,
                columns,
                by_state,
                by_tear,
                program,
            });
        }
        Some(LoopCorrection { blocks, tear_at })
    }

    /// The states tear `k` depends on, increasing.
    pub(super) fn columns_of(&self, k: usize) -> &[usize] {
        self.tear_at
            .get(k)
            .and_then(|&(b, _)| self.blocks.get(b))
            .map_or(&[], |b| b.columns.as_slice())
    }

    /// `∂z/∂x` at `values`, whose inputs hold the loops' solution at the point.
    pub(super) fn slopes(&self, values: &Values<'_>, stack: &mut Vec<f64>) -> TearSlopes {
        let mut solved: Vec<Mat> = Vec::with_capacity(self.blocks.len());
        // The derivatives' values are appended after the inputs, where the programs read them.
        let mut inputs = values.inputs.to_vec();
        let base = inputs.len();
        for (b, block) in self.blocks.iter().enumerate() {
            inputs.truncate(base);
            block.program.eval_appending(values, &mut inputs, stack);
            let mut derivatives = inputs.iter().skip(base).copied();
            let size = block.tears.len();
            let width = block.columns.len();
            // One residual per tear: `∂r_b/∂z_b` is square.
            let mut own = dense::zeros(size, size);
            let mut rhs = dense::zeros(size, width);
            let rows = own.iter_mut().zip(rhs.iter_mut());
            for ((own, rhs), (by_state, by_tear)) in
                rows.zip(block.by_state.iter().zip(&block.by_tear))
            {
                for &at in by_state {
                    let slope = derivatives.next().unwrap_or(f64::NAN);
                    rhs.get_mut(at).into_iter().for_each(|v| *v += slope);
                }
                for &k in by_tear {
                    let slope = derivatives.next().unwrap_or(f64::NAN);
                    match self.tear_at.get(k) {
                        Some(&(owner, row)) if owner == b => {
                            own.get_mut(row).into_iter().for_each(|v| *v = slope);
                        }
                        // ∂r/∂z_k ∂z_k/∂x, from the earlier block's columns into this block's.
                        Some(&(owner, row)) => {
                            let columns = self.blocks.get(owner).map_or(&[][..], |e| &e.columns);
                            let values = solved.get(owner).and_then(|m| m.get(row));
                            for (c, v) in columns.iter().zip(values.into_iter().flatten()) {
                                if let Ok(at) = block.columns.binary_search(c) {
                                    rhs[at] += slope * v;
                                }
                            }
                        }
                        None => rhs.fill(f64::NAN),
                    }
                }
            }
            let slopes = dense::solve(&own, &rhs)
                .map(|m| {
                    m.into_iter()
                        .map(|row| row.into_iter().map(|v| -v).collect())
                        .collect()
                })
                .unwrap_or_else(|| vec![vec![f64::NAN; width]; size]);
            solved.push(slopes);
        }
        TearSlopes(solved)
    }
}

impl TearSlopes {
    /// `∂z_k/∂x` at the column position `at` of tear `k`'s columns.
    pub(super) fn get(&self, correction: &LoopCorrection, k: usize, at: usize) -> f64 {
        correction
            .tear_at
            .get(k)
            .and_then(|&(b, row)| self.0.get(b)?.get(row)?.get(at).copied())
            .unwrap_or(f64::NAN)
    }
}

/// The tears of the loops in block order (their global indices), and each one's index.
pub(super) struct Tears {
    syms: Vec<Sym>,
    index: HashMap<Sym, usize>,
}

/// Compiles expressions into one program (what they share computed once), for the message `what`.
pub(super) type CompileSeq<'a> = &'a dyn Fn(&[Expr], &str) -> Result<ProgramSeq, SimError>;

/// Derivatives by states or by tears: `(state or global tear, derivative)`.
pub(super) type Derivatives = Vec<(usize, Expr)>;

impl Tears {
    pub(super) fn new(loops: &[TearBlock]) -> Tears {
        let syms: Vec<Sym> = loops.iter().flat_map(|b| b.tears.iter().copied()).collect();
        let index = syms.iter().enumerate().map(|(k, &z)| (z, k)).collect();
        Tears { syms, index }
    }

    pub(super) fn len(&self) -> usize {
        self.syms.len()
    }

    /// The symbol of global tear `k`.
    fn sym(&self, k: usize) -> Option<Sym> {
        self.syms.get(k).copied()
    }

    /// The states below `n` and the tears (global indices) that `e` reads, each once, increasing.
    pub(super) fn partition(&self, e: &Expr, n: usize) -> (Vec<usize>, Vec<usize>) {
        let mut states = Vec::new();
        let mut tears = Vec::new();
        for s in e.syms() {
            match s {
                Sym::State(c) if c < n => states.push(c),
                Sym::Tear(_) => tears.extend(self.index.get(&s).copied()),
                _ => {}
            }
        }
        states.sort_unstable();
        states.dedup();
        tears.sort_unstable();
        tears.dedup();
        (states, tears)
    }

    /// The nonzero derivatives of `e` by `states` and by the tears `tears` (global indices); `None` when `e` uses a
    /// function without a derivative.
    pub(super) fn derivatives(
        &self,
        e: &Expr,
        (states, tears): (&[usize], &[usize]),
    ) -> Option<(Derivatives, Derivatives)> {
        let wrt: Vec<Sym> = states
            .iter()
            .map(|&c| Sym::State(c))
            .chain(tears.iter().filter_map(|&k| self.sym(k)))
            .collect();
        let grads = symbols::gradient(e, &wrt).ok()?;
        let (by_state, by_tear) = grads.split_at(states.len().min(grads.len()));
        let nonzero = |at: &[usize], ds: &[Expr]| -> Derivatives {
            at.iter()
                .zip(ds)
                .filter(|(_, d)| !d.is_zero())
                .map(|(&k, d)| (k, d.clone()))
                .collect()
        };
        Some((nonzero(states, by_state), nonzero(tears, by_tear)))
    }
}
