//! The nonlinear algebraic loops of a simulation ([`crate::equations::TearBlock`]), compiled, and their solution at
//! every evaluation of the rates or outputs.
//!
//! The tear variables live at the end of the vector the programs read as inputs (`[u, u̇, z]`, see
//! [`super::System`]); each block's residuals `r`, residual scales and Jacobian `∂r/∂z` (symbolic derivatives) are
//! programs over that vector. [`Loops::solve`] solves the blocks in order by damped Newton
//! ([`crate::equations::newton`]), warm-started from the values the vector already holds (the previous
//! evaluation's solution); when that fails it retries from zero before reporting the block, the time and the
//! residual ([`LoopFailure`]).

use super::program::{Program, Values};
use crate::equations::LoopFailure;
use crate::equations::newton::{self, Lu, Problem, Settings};

/// The compiled blocks of a model, in solving order.
#[derive(Clone, Debug, Default)]
pub struct Loops {
    blocks: Vec<BlockPrograms>,
}

/// The compiled programs of one block.
#[derive(Clone, Debug)]
pub struct BlockPrograms {
    /// The tears' positions in the programs' input vector.
    pub slots: Vec<usize>,
    pub names: Vec<String>,
    pub residuals: Vec<Program>,
    pub scales: Vec<Program>,
    /// Row-major `∂r_i/∂z_j`.
    pub jacobian: Vec<Program>,
    /// `∂r/∂z` factored, when it reads parameters only (a linear loop): the block is then solved by steps with
    /// this factorisation, not by evaluating and factoring its Jacobian at every solve.
    pub constant: Option<Lu>,
}

impl Loops {
    /// Adds a block (after the blocks it refers to).
    pub fn push(&mut self, block: BlockPrograms) {
        self.blocks.push(block);
    }

    /// True when the model has no nonlinear algebraic loops.
    pub fn is_empty(&self) -> bool {
        self.blocks.is_empty()
    }

    /// Solves every block at `values` (whose `inputs` are ignored) and writes the tears into `ext`, the programs'
    /// input vector, from whose tear slots the iteration starts.
    pub fn solve(
        &self,
        values: &Values<'_>,
        ext: &mut [f64],
        stack: &mut Vec<f64>,
    ) -> Result<(), LoopFailure> {
        for block in &self.blocks {
            let mut z: Vec<f64> = block
                .slots
                .iter()
                .map(|&s| ext.get(s).copied().filter(|v| v.is_finite()).unwrap_or(0.0))
                .collect();
            let warm = z.iter().any(|v| *v != 0.0);
            let mut problem = Compiled {
                block,
                values,
                ext: &mut *ext,
                stack: &mut *stack,
            };
            // A linear loop: from the last solution, else from zero (where a loop whose terms have all but vanished
            // lands exactly: rounding keeps the residual from ever being small against terms of that size).
            if let Some(lu) = &block.constant {
                let solved = [z.clone(), vec![0.0; z.len()]]
                    .into_iter()
                    .find_map(|mut from| {
                        newton::solve_affine(&mut problem, lu, &mut from, Settings::default())
                            .then_some(from)
                    });
                if let Some(solved) = solved {
                    problem.place(&solved);
                    continue;
                }
            }
            let mut result = newton::solve(&mut problem, &mut z, Settings::default());
            if result.is_err() && warm {
                z.iter_mut().for_each(|v| *v = 0.0);
                result = newton::solve(&mut problem, &mut z, Settings::default());
            }
            if let Err(failure) = result {
                return Err(LoopFailure {
                    tears: block.names.clone(),
                    worst: block.names.get(failure.index).cloned().unwrap_or_default(),
                    failure,
                });
            }
            problem.place(&z);
        }
        Ok(())
    }
}

/// A block evaluated by its programs.
struct Compiled<'a, 'v> {
    block: &'a BlockPrograms,
    values: &'a Values<'v>,
    ext: &'a mut [f64],
    stack: &'a mut Vec<f64>,
}

impl Compiled<'_, '_> {
    fn place(&mut self, z: &[f64]) {
        for (&slot, v) in self.block.slots.iter().zip(z) {
            if let Some(x) = self.ext.get_mut(slot) {
                *x = *v;
            }
        }
    }

    fn eval(&mut self, programs: &[Program], out: &mut [f64]) {
        let v = Values {
            inputs: self.ext,
            ..*self.values
        };
        for (o, p) in out.iter_mut().zip(programs) {
            *o = p.eval(&v, self.stack);
        }
    }
}

impl Problem for Compiled<'_, '_> {
    fn size(&self) -> usize {
        self.block.slots.len()
    }

    fn residual(&mut self, z: &[f64], r: &mut [f64], scale: &mut [f64]) {
        self.place(z);
        let block = self.block;
        self.eval(&block.residuals, r);
        self.eval(&block.scales, scale);
    }

    fn jacobian(&mut self, z: &[f64], jac: &mut [f64]) {
        self.place(z);
        let block = self.block;
        self.eval(&block.jacobian, jac);
    }
}
