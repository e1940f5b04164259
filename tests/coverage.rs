//! The statistics of a fit repeated over seeded noisy records at known parameters: the reports must cover the
//! truth and their standard errors must describe the spread of the estimates.

use bgc_runtime::fit::FitReport;

/// The fits of one study, collected record by record.
pub struct Coverage {
    truth: Vec<f64>,
    covered: usize,
    records: usize,
    estimates: Vec<Vec<f64>>,
    errors: Vec<Vec<f64>>,
}

impl Coverage {
    /// A study of the fitted parameters whose true values are `truth` (in the report's order).
    pub fn new(truth: Vec<f64>) -> Coverage {
        let n = truth.len();
        Coverage {
            truth,
            covered: 0,
            records: 0,
            estimates: vec![Vec::new(); n],
            errors: vec![Vec::new(); n],
        }
    }

    /// Adds the fit of record `seed`, which must have converged with every parameter determined.
    pub fn add(&mut self, seed: u64, r: &FitReport) {
        assert!(r.convergence.converged(), "seed {seed}: {:?}", r.stop);
        assert!(
            r.undetermined.is_empty(),
            "seed {seed}: {:?}",
            r.undetermined
        );
        let inside = r
            .estimates
            .iter()
            .zip(&self.truth)
            .all(|(e, t)| (e.value - t).abs() <= 3.0 * e.std_error);
        self.covered += usize::from(inside);
        self.records += 1;
        for (k, e) in r.estimates.iter().enumerate() {
            self.estimates[k].push(e.value);
            self.errors[k].push(e.std_error);
        }
    }

    /// At least 95 % of the records cover the truth within 3 standard errors (a 3σ interval misses 0.27 % of the
    /// time); for each parameter the mean reported standard error agrees with the spread of the estimates to
    /// within 30 %, and the mean estimate lies within 4 standard errors of the mean of the truth (unbiased).
    pub fn check(&self, names: &[&str]) {
        assert!(
            100 * self.covered >= 95 * self.records,
            "only {} of {} records cover the truth within 3 standard errors",
            self.covered,
            self.records
        );
        for (k, name) in names.iter().enumerate() {
            let n = self.estimates[k].len() as f64;
            let mean = self.estimates[k].iter().sum::<f64>() / n;
            let spread = (self.estimates[k]
                .iter()
                .map(|e| (e - mean).powi(2))
                .sum::<f64>()
                / (n - 1.0))
                .sqrt();
            let reported = self.errors[k].iter().sum::<f64>() / n;
            assert!(
                (0.7..=1.3).contains(&(reported / spread)),
                "{name}: reported {reported:e}, spread {spread:e}"
            );
            assert!(
                (mean - self.truth[k]).abs() < 4.0 * spread / n.sqrt(),
                "{name}: mean {mean:e}, truth {:e}",
                self.truth[k]
            );
        }
    }
}
