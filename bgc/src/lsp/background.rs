//! The equations stage of large documents, on a thread of its own.
//!
//! Deriving the equations of ten thousand elements takes seconds, the rest of the analysis tens of milliseconds.
//! For a large document the server publishes the front end's diagnostics at once and hands the analysis to this
//! worker, which derives the equations and publishes the complete diagnostics of that version, unless the document
//! changed meanwhile (then the result is dropped and the newest version is worked on next). Every publication for
//! a document, the server's and the worker's, happens under one lock together with the update of the document's
//! newest version, so a client never receives an older version's diagnostics after a newer one's.

use super::analysis::{Analysis, derive_equations};
use std::collections::{BTreeMap, HashMap};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};

/// A document's analysis waiting for its equations.
pub struct Job {
    pub version: i32,
    pub analysis: Analysis,
}

#[derive(Default)]
struct State {
    pending: BTreeMap<String, Job>,
    /// The newest version of each document the server has published.
    newest: HashMap<String, i32>,
    /// Analyses completed with their equations, by document.
    done: HashMap<String, (i32, Analysis)>,
    stop: bool,
}

#[derive(Default)]
struct Shared {
    state: Mutex<State>,
    wake: Condvar,
}

/// Sends the diagnostics of an analysis for a document and version.
pub type Publish = dyn Fn(&str, i32, &Analysis) + Send + Sync;

pub struct Worker {
    shared: Arc<Shared>,
}

impl Worker {
    pub fn start(publish: Arc<Publish>) -> Worker {
        let shared = Arc::new(Shared::default());
        let theirs = Arc::clone(&shared);
        let spawned = std::thread::Builder::new()
            .name("bgc-lsp-equations".into())
            .spawn(move || work(&theirs, &*publish));
        if let Err(e) = spawned {
            eprintln!(
                "bgc lsp: no thread for the equations of large documents ({e}); they are left out"
            );
        }
        Worker { shared }
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        self.shared
            .state
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Records `version` as the document's newest and runs `publish` (which sends its diagnostics) under the lock;
    /// with a job, queues it in place of any older one of the document.
    pub fn publish(&self, uri: &str, version: i32, job: Option<Job>, publish: impl FnOnce()) {
        let mut state = self.lock();
        state.newest.insert(uri.to_string(), version);
        state.pending.remove(uri);
        publish();
        if let Some(job) = job {
            state.pending.insert(uri.to_string(), job);
            self.shared.wake.notify_one();
        }
    }

    /// The analyses completed since the last call.
    pub fn take_done(&self) -> Vec<(String, i32, Analysis)> {
        self.lock()
            .done
            .drain()
            .map(|(uri, (version, analysis))| (uri, version, analysis))
            .collect()
    }

    /// A document closed: nothing of it is published any more.
    pub fn forget(&self, uri: &str) {
        let mut state = self.lock();
        state.pending.remove(uri);
        state.newest.insert(uri.to_string(), i32::MIN);
        state.done.remove(uri);
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        self.lock().stop = true;
        self.shared.wake.notify_all();
    }
}

fn work(shared: &Shared, publish: &Publish) {
    loop {
        let (uri, job) = {
            let mut state = shared.state.lock().unwrap_or_else(|p| p.into_inner());
            loop {
                if state.stop {
                    return;
                }
                if let Some(next) = state.pending.pop_first() {
                    break next;
                }
                state = shared.wake.wait(state).unwrap_or_else(|p| p.into_inner());
            }
        };
        let mut analysis = job.analysis;
        if catch_unwind(AssertUnwindSafe(|| derive_equations(&mut analysis))).is_err() {
            eprintln!("bgc lsp: the equations of {uri} failed; its other diagnostics stay");
            continue;
        }
        let mut state = shared.state.lock().unwrap_or_else(|p| p.into_inner());
        if state.newest.get(&uri) == Some(&job.version) {
            publish(&uri, job.version, &analysis);
            state.done.insert(uri, (job.version, analysis));
        }
    }
}
