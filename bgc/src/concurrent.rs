//! Two independent computations at once. A large model's derivation and code generation spend seconds in passes
//! that do not depend on each other (the readable form and the energy terms; the Jacobians of the code generation
//! plan), and most machines have a second core for one of them. The results do not depend on which thread
//! computed them (expressions are hash-consed values, and no order or name is taken from an address), so the
//! output is the same as when they run one after the other, which is what happens when no thread can be started.

use std::thread;

/// The stack of the helper thread: the main thread's usual size, so that the work does not depend on which
/// thread it runs on.
const STACK_BYTES: usize = 8 << 20;

/// `(background(), foreground())`, the first on a helper thread while the calling thread computes the second (or
/// after it, when no thread can be started). A panic in either is propagated, as if they had run in turn. The
/// background computation may own what it works on (a copy of a writer with its own caches).
pub(crate) fn join<A: Send, B>(
    background: impl FnOnce() -> A + Send,
    foreground: impl FnOnce() -> B,
) -> (A, B) {
    // Behind a lock, so that the calling thread can still run it when no thread can be started: `run` holds only
    // a reference, so the thread takes a copy of it and the calling thread keeps one.
    let slot = std::sync::Mutex::new(Some(background));
    let run = || {
        let f = slot
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .take();
        f.map(|f| f())
    };
    let (a, b) = thread::scope(|scope| {
        let helper = thread::Builder::new()
            .name("bgc-worker".into())
            .stack_size(STACK_BYTES)
            .spawn_scoped(scope, run);
        let b = foreground();
        let a = match helper {
            Ok(handle) => handle
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic)),
            Err(_) => run(),
        };
        (a, b)
    });
    match a {
        Some(a) => (a, b),
        // The closure is taken out of its slot once, by the thread or after it could not start.
        None => unreachable!("the background computation did not run"),
    }
}

/// Below this many items, [`map_halves`] maps on the calling thread: starting a thread costs more than the work.
const PARALLEL_ITEMS: usize = 4096;

/// `items.iter().map(f)`, in order, the first half on a helper thread when there are many items. For passes that
/// handle each element of a large model on its own (the definitions of each node, the text of each equation).
pub(crate) fn map_halves<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    if items.len() < PARALLEL_ITEMS {
        return items.iter().map(&f).collect();
    }
    let (first, second) = items.split_at(items.len() / 2);
    let (mut out, rest) = join(
        || first.iter().map(&f).collect::<Vec<R>>(),
        || second.iter().map(&f).collect::<Vec<R>>(),
    );
    out.extend(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::{PARALLEL_ITEMS, join, map_halves};

    #[test]
    fn halves_are_mapped_in_order_on_both_sides_of_the_threshold() {
        for n in [0, 7, PARALLEL_ITEMS, 3 * PARALLEL_ITEMS + 1] {
            let items: Vec<usize> = (0..n).collect();
            let mapped = map_halves(&items, |&k| 2 * k + 1);
            assert_eq!(
                mapped,
                (0..n).map(|k| 2 * k + 1).collect::<Vec<_>>(),
                "{n} items"
            );
        }
    }

    #[test]
    fn an_owned_background_computation_gives_back_what_it_built() {
        let mut owned = vec![1u64, 2, 3];
        let mut shared = vec![10u64];
        let (built, ()) = join(
            move || {
                owned.push(4);
                owned
            },
            || shared.push(20),
        );
        assert_eq!((built, shared), (vec![1, 2, 3, 4], vec![10, 20]));
    }

    #[test]
    fn both_results_come_back_in_their_places() {
        let data: Vec<u64> = (1..=1000).collect();
        let (sum, product) = join(
            || data.iter().sum::<u64>(),
            || data.iter().take(10).product::<u64>(),
        );
        assert_eq!((sum, product), (500_500, 3_628_800));
    }
}
