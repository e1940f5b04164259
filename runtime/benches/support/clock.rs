//! The core clock of the bench machine, measured, so that a time can be compared with a bound counted in cycles.
//!
//! A flop bound is a number of cycles (flops at 4 per cycle); what it is in nanoseconds depends on the clock the
//! core runs at while the bench runs, which varies between machines (and with turbo and load). This bench times
//! a chain of 1,000 dependent 64-bit integer multiplications, each of which takes 3 cycles on every x86-64 core
//! of the last fifteen years (Intel since Nehalem, AMD since Zen), so `clock_3000_cycles` takes 3,000 cycles:
//! the clock in GHz is 3,000 divided by its time in nanoseconds, and a bound of `c` cycles is `c / GHz` ns.
//! Integer multiplications are used because no core shortens their chain (a chain of small additions can be
//! folded at rename on recent Intel cores) and their latency is the same on both vendors (that of `mulsd`
//! is not).

use criterion::Criterion;

/// Times 3,000 cycles (x86-64 only; elsewhere there is no such bench).
pub fn clock(c: &mut Criterion) {
    #[cfg(target_arch = "x86_64")]
    c.bench_function("clock_3000_cycles", |b| {
        b.iter(|| imul_chain(std::hint::black_box(3)))
    });
    #[cfg(not(target_arch = "x86_64"))]
    let _ = c;
}

/// 1,000 dependent `imul`s, 3 cycles each.
#[cfg(target_arch = "x86_64")]
fn imul_chain(mut x: u64) -> u64 {
    for _ in 0..100 {
        // SAFETY: register-only arithmetic; no memory, stack or flags the compiler relies on.
        unsafe {
            core::arch::asm!(
                "imul {x}, {x}", "imul {x}, {x}", "imul {x}, {x}", "imul {x}, {x}", "imul {x}, {x}",
                "imul {x}, {x}", "imul {x}, {x}", "imul {x}, {x}", "imul {x}, {x}", "imul {x}, {x}",
                x = inout(reg) x,
                options(pure, nomem, nostack),
            );
        }
    }
    x
}
