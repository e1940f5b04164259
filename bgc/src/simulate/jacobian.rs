//! The symbolic Jacobian `∂rate/∂x` of a compiled system, mass-matrix rows included.
//!
//! A rate is differentiated term by term, each term only by the states it reads ([`symbolic`]). The rows of a mass
//! block (an I-field, inertias coupled through a varying modulus) hold the generalised forces `F` of
//! `M(q) ẋ_B = F`, so their entries are those of the rates only after the block is solved at the point:
//!
//! ```text
//! ∂ẋ_B/∂x_c = M⁻¹ (∂F/∂x_c − (∂M/∂x_c) ẋ_B)
//! ```
//!
//! in the columns `c` where `∂F` or `M` has an entry. Each block is solved with its own `M`, so a model of many
//! separate mechanisms keeps a sparse Jacobian (before, such models took finite differences of the whole rhs, one
//! column at a time, and a dense factorisation).

use super::loop_jacobian::{LoopCorrection, Tears};
use super::program::{Program, Values};
use super::{MassPrograms, SimError};
use crate::equations::MassBlock;
use crate::equations::dense::{self, Mat};
use crate::equations::symbols::{self, Sym, add, states_read};
use crate::symbolic::{Expr, Node};
use std::collections::BTreeMap;

/// Where an entry's value comes from.
#[derive(Clone, Debug)]
enum Source {
    /// A rate's derivative, compiled.
    Direct(Program),
    /// Row `row` of mass block `block`, at its `column`-th column.
    Block {
        block: usize,
        row: usize,
        column: usize,
    },
    /// A rate that reads tears: its derivative holding them fixed (if any) plus `Σ ∂f/∂z_k ∂z_k/∂x`, over
    /// `(the rate's k-th tear derivative, the column's position among tear k's columns)`.
    Loop {
        direct: Option<Program>,
        via: Vec<(usize, usize)>,
    },
}

/// The rows of one mass block (the system's block of the same index supplies its states and `M`).
#[derive(Clone, Debug)]
struct BlockRows {
    /// The columns of its rows: those where `∂F` or `M` has an entry, increasing.
    columns: Vec<usize>,
    /// Per row of the block: `(column index, ∂F_row/∂x_column)`.
    force: Vec<Vec<(usize, Program)>>,
    /// `(column index, i, j, ∂M_ij/∂x_column)`.
    slopes: Vec<(usize, usize, usize, Program)>,
}

/// The compiled Jacobian of the rates over the model states.
#[derive(Clone, Debug)]
pub(super) struct Jacobian {
    /// `(row, column, source)`, row by row.
    entries: Vec<(usize, usize, Source)>,
    blocks: Vec<BlockRows>,
    /// The nonlinear algebraic loops' derivatives, when the model has loops.
    loops: Option<LoopCorrection>,
    /// Per rate: `(global tear k, ∂f/∂z_k)`.
    through: Vec<Vec<(usize, Program)>>,
}

impl Jacobian {
    /// The Jacobian of `rates` over the `n` model states, with the rows of `mass` solved and the tears of the
    /// loops moving with the states ([`super::loop_jacobian`]); `None` when a rate or a mass entry uses a function
    /// without a derivative, the model has both loops and mass blocks, or the loops make more than
    /// `max_loop_entries` entries (the caller then takes finite differences).
    pub(super) fn new(
        rates: &[(Expr, String)],
        n: usize,
        mass: &[MassBlock],
        loops: Option<(Tears, LoopCorrection)>,
        max_loop_entries: usize,
        compile: &dyn Fn(&Expr, &str) -> Result<Program, SimError>,
    ) -> Option<Jacobian> {
        let (tears, correction) = match loops {
            Some((tears, correction)) if mass.is_empty() => (tears, Some(correction)),
            Some(_) => return None,
            None => (Tears::new(&[]), None),
        };
        let mut direct: Vec<Vec<(usize, Program)>> = vec![Vec::new(); rates.len()];
        let mut through: Vec<Vec<(usize, Program)>> = vec![Vec::new(); rates.len()];
        for (r, c, p) in symbolic(rates, n, &tears, &mut through, compile)? {
            direct[r].push((c, p));
        }
        if let Some(correction) = &correction {
            // At least the widest tear's columns in every row that reads tears: refuse a dense Jacobian before
            // building it.
            let least: usize = through
                .iter()
                .map(|row| {
                    row.iter()
                        .map(|(k, _)| correction.columns_of(*k).len())
                        .max()
                        .unwrap_or(0)
                })
                .sum();
            if least > max_loop_entries {
                return None;
            }
        }
        let mut block_of: BTreeMap<usize, (usize, usize)> = BTreeMap::new();
        let mut blocks = Vec::with_capacity(mass.len());
        for (b, rows) in mass.iter().enumerate() {
            let block = BlockRows::new(rows, &mut direct, n, compile)?;
            for (i, &s) in rows.states.iter().enumerate() {
                block_of.insert(s, (b, i));
            }
            blocks.push(block);
        }
        let mut entries = Vec::new();
        for (r, row) in direct.into_iter().enumerate() {
            match block_of.get(&r) {
                Some(&(block, i)) => {
                    let columns = &blocks[block].columns;
                    entries.extend(columns.iter().enumerate().map(|(column, &c)| {
                        let source = Source::Block {
                            block,
                            row: i,
                            column,
                        };
                        (r, c, source)
                    }));
                }
                None => match (&correction, through.get(r).filter(|t| !t.is_empty())) {
                    (Some(correction), Some(tears_read)) => {
                        entries.extend(loop_row(r, row, tears_read, correction));
                        if entries.len() > max_loop_entries {
                            return None;
                        }
                    }
                    _ => entries.extend(row.into_iter().map(|(c, p)| (r, c, Source::Direct(p)))),
                },
            }
        }
        Some(Jacobian {
            entries,
            blocks,
            loops: correction,
            through,
        })
    }

    /// The positions `(row, column)` of the entries, row by row.
    pub(super) fn pattern(&self) -> Vec<(usize, usize)> {
        self.entries.iter().map(|(r, c, _)| (*r, *c)).collect()
    }

    /// Whether the entries take the loops' derivatives, so that the loops must be solved at the point first.
    pub(super) fn through_loops(&self) -> bool {
        self.loops.is_some()
    }

    /// Calls `each(row, column, value)` for every entry at the point (all NaN in the rows of a block whose `M`
    /// is singular there); `rates` evaluates the generalised forces of the block rows, `mass` the blocks (those
    /// [`Jacobian::new`] was given, compiled, in the same order). `values` holds the loops' solution at the point.
    pub(super) fn for_each(
        &self,
        values: &Values<'_>,
        (rates, mass): (&[Program], &[MassPrograms]),
        stack: &mut Vec<f64>,
        mut each: impl FnMut(usize, usize, f64),
    ) {
        let solved: Vec<Mat> = self
            .blocks
            .iter()
            .zip(mass)
            .map(|(b, block)| b.solve(block, values, rates, stack))
            .collect();
        let slopes = self.loops.as_ref().map(|l| l.slopes(values, stack));
        // The current loop row's `∂f/∂z`, evaluated once per row.
        let mut row_at = usize::MAX;
        let mut by_tear: Vec<f64> = Vec::new();
        for (r, c, source) in &self.entries {
            let v = match source {
                Source::Direct(p) => p.eval(values, stack),
                Source::Block { block, row, column } => solved
                    .get(*block)
                    .and_then(|m| m.get(*row))
                    .and_then(|row| row.get(*column))
                    .copied()
                    .unwrap_or(f64::NAN),
                Source::Loop { direct, via } => {
                    let tears = self.through.get(*r).map_or(&[][..], Vec::as_slice);
                    if row_at != *r {
                        row_at = *r;
                        by_tear.clear();
                        by_tear.extend(tears.iter().map(|(_, p)| p.eval(values, stack)));
                    }
                    let mut v = direct.as_ref().map_or(0.0, |p| p.eval(values, stack));
                    if let (Some(loops), Some(slopes)) = (&self.loops, &slopes) {
                        for &(slot, at) in via {
                            let k = tears.get(slot).map_or(usize::MAX, |(k, _)| *k);
                            v += by_tear.get(slot).copied().unwrap_or(f64::NAN)
                                * slopes.get(loops, k, at);
                        }
                    }
                    v
                }
            };
            each(*r, *c, v);
        }
    }
}

impl BlockRows {
    /// Takes the block's rows out of `direct` (the entries of `∂F`) and differentiates `M`.
    fn new(
        rows: &MassBlock,
        direct: &mut [Vec<(usize, Program)>],
        n: usize,
        compile: &dyn Fn(&Expr, &str) -> Result<Program, SimError>,
    ) -> Option<BlockRows> {
        let size = rows.states.len();
        let what = "the mass matrix";
        let forces: Vec<Vec<(usize, Program)>> = rows
            .states
            .iter()
            .map(|&s| direct.get_mut(s).map(std::mem::take).unwrap_or_default())
            .collect();
        let mut slopes_by_state = Vec::new();
        for (k, e) in rows.matrix.iter().flatten().enumerate() {
            let read = states_read(e, n);
            let wrt: Vec<Sym> = read.iter().map(|&c| Sym::State(c)).collect();
            for (c, d) in read.into_iter().zip(symbols::gradient(e, &wrt).ok()?) {
                if !d.is_zero() {
                    slopes_by_state.push((c, k / size, k % size, compile(&d, what).ok()?));
                }
            }
        }
        let mut columns: Vec<usize> = forces
            .iter()
            .flatten()
            .map(|(c, _)| *c)
            .chain(slopes_by_state.iter().map(|(c, ..)| *c))
            .collect();
        columns.sort_unstable();
        columns.dedup();
        let index = |c: usize| columns.binary_search(&c).unwrap_or_default();
        let force = forces
            .into_iter()
            .map(|row| row.into_iter().map(|(c, p)| (index(c), p)).collect())
            .collect();
        let slopes = slopes_by_state
            .into_iter()
            .map(|(c, i, j, p)| (index(c), i, j, p))
            .collect();
        Some(BlockRows {
            columns,
            force,
            slopes,
        })
    }

    /// The block's rows of `∂ẋ/∂x` over its columns at the point: `M⁻¹ (∂F − (∂M/∂x_c) ẋ_B)`; NaN when `M` is
    /// singular.
    fn solve(
        &self,
        block: &MassPrograms,
        values: &Values<'_>,
        rates: &[Program],
        stack: &mut Vec<f64>,
    ) -> Mat {
        let size = block.states.len();
        let m = block.at(values, stack);
        let forces: Mat = block
            .states
            .iter()
            .map(|&s| vec![rates.get(s).map_or(f64::NAN, |p| p.eval(values, stack))])
            .collect();
        let nan = || vec![vec![f64::NAN; self.columns.len()]; size];
        let Some(rates_b) = dense::solve(&m, &forces) else {
            return nan();
        };
        let mut rhs = vec![vec![0.0; self.columns.len()]; size];
        for (i, row) in self.force.iter().enumerate() {
            for (c, p) in row {
                rhs[i][*c] = p.eval(values, stack);
            }
        }
        for (c, i, j, p) in &self.slopes {
            rhs[*i][*c] -= p.eval(values, stack) * rates_b[*j][0];
        }
        dense::solve(&m, &rhs).unwrap_or_else(nan)
    }
}

/// The nonzero entries of `∂rate/∂x` over the model states (the quadrature states enter no rate).
///
/// A sum is differentiated term by term, each term only by the states it reads: the dissipated power sums a term
/// per resistor, and differentiating the whole sum by every state it reads would be quadratic in the model.
/// The derivatives by the tears of `tears` go into `through`, a row per rate.
fn symbolic(
    rates: &[(Expr, String)],
    n: usize,
    tears: &Tears,
    through: &mut [Vec<(usize, Program)>],
    compile: &dyn Fn(&Expr, &str) -> Result<Program, SimError>,
) -> Option<Vec<(usize, usize, Program)>> {
    let mut entries = Vec::new();
    for (r, (e, what)) in rates.iter().enumerate() {
        let terms = match e.node() {
            Node::Add(terms) => terms.as_slice(),
            _ => std::slice::from_ref(e),
        };
        let mut parts: BTreeMap<usize, Vec<Expr>> = Default::default();
        let mut tear_parts: BTreeMap<usize, Vec<Expr>> = Default::default();
        for term in terms {
            // Each term only by the states (and tears) it reads, all in one walk of it when they are many (a long
            // sum held whole).
            let (read, tears_read) = tears.partition(term, n);
            let (by_state, by_tear) = tears.derivatives(term, (&read, &tears_read))?;
            for (c, d) in by_state {
                parts.entry(c).or_default().push(d);
            }
            for (k, d) in by_tear {
                tear_parts.entry(k).or_default().push(d);
            }
        }
        for (c, part) in parts {
            let d = add(part);
            if !d.is_zero() {
                entries.push((r, c, compile(&d, what).ok()?));
            }
        }
        for (k, part) in tear_parts {
            let d = add(part);
            if !d.is_zero() {
                through.get_mut(r)?.push((k, compile(&d, what).ok()?));
            }
        }
    }
    Some(entries)
}

/// The entries of rate `r`, which reads the tears `tears_read`: over its direct columns and those its tears
/// depend on, increasing.
fn loop_row(
    r: usize,
    direct: Vec<(usize, Program)>,
    tears_read: &[(usize, Program)],
    loops: &LoopCorrection,
) -> Vec<(usize, usize, Source)> {
    // Per column: the derivative holding the tears fixed, and the `(tear slot, column position)` pairs.
    type Column = (Option<Program>, Vec<(usize, usize)>);
    let mut columns: BTreeMap<usize, Column> = BTreeMap::new();
    for (c, p) in direct {
        columns.entry(c).or_default().0 = Some(p);
    }
    for (slot, (k, _)) in tears_read.iter().enumerate() {
        for (at, &c) in loops.columns_of(*k).iter().enumerate() {
            columns.entry(c).or_default().1.push((slot, at));
        }
    }
    columns
        .into_iter()
        .map(|(c, (direct, via))| (r, c, Source::Loop { direct, via }))
        .collect()
}
