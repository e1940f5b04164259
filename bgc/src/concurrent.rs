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
/// after it, when no thread can be started). A panic in either is propagated, as if they had run in turn.
pub(crate) fn join<A: Send, B>(
    background: impl Fn() -> A + Sync,
    foreground: impl FnOnce() -> B,
) -> (A, B) {
    thread::scope(|scope| {
        let helper = thread::Builder::new()
            .name("bgc-worker".into())
            .stack_size(STACK_BYTES)
            .spawn_scoped(scope, &background);
        let b = foreground();
        let a = match helper {
            Ok(handle) => handle
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic)),
            Err(_) => background(),
        };
        (a, b)
    })
}

#[cfg(test)]
mod tests {
    use super::join;

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
