"""Times scipy.linalg.solve_continuous_are and slycot's sb02md (through python-control) on the CARE of
care_chain.rs (the same damped mass-spring chain, Q = I, R = 1) and prints the median of each with the
relative residual of the solution. Run after `cargo bench -p bgc-runtime --bench care_chain`:

    python3 runtime/benches/care_chain_reference.py
"""

import statistics
import time

import numpy as np
import scipy.linalg as sl

try:
    import control
    import slycot  # noqa: F401
except ImportError:  # slycot is optional
    control = None


def chain(n, k=1.0, c=0.1):
    masses = n // 2
    a = np.zeros((n, n))
    for i in range(masses):
        q, v = 2 * i, 2 * i + 1
        a[q, v] = 1.0
        neighbours = 2.0 if i + 1 < masses else 1.0
        a[v, q] = -k * neighbours
        a[v, v] = -c * neighbours
        if i > 0:
            a[v, q - 2] = k
            a[v, v - 2] = c
        if i + 1 < masses:
            a[v, q + 2] = k
            a[v, v + 2] = c
    b = np.zeros((n, 1))
    b[n - 1, 0] = 1.0
    return a, b, np.eye(n), np.eye(1)


def residual(a, b, q, r, x):
    g = b @ np.linalg.solve(r, b.T)
    res = a.T @ x + x @ a - x @ g @ x + q
    terms = 2 * np.linalg.norm(x @ a) + np.linalg.norm(x @ g @ x) + np.linalg.norm(q)
    return np.linalg.norm(res) / terms


def median_ms(f, repeats):
    f()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return 1e3 * statistics.median(times)


for n in [20, 50, 100, 200]:
    a, b, q, r = chain(n)
    repeats = 20 if n <= 100 else 7
    x = sl.solve_continuous_are(a, b, q, r)
    line = f"n = {n:3}: scipy {median_ms(lambda: sl.solve_continuous_are(a, b, q, r), repeats):8.2f} ms"
    line += f" (residual {residual(a, b, q, r, x):.1e})"
    if control is not None:
        xs, _, _ = control.care(a, b, q, r, method="slycot")
        t = median_ms(lambda: control.care(a, b, q, r, method="slycot"), repeats)
        line += f", slycot {t:8.2f} ms (residual {residual(a, b, q, r, xs):.1e})"
    print(line)
