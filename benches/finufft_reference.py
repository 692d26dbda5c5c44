"""FINUFFT on the job of benches/spectrum.rs (a): 100 random sets of N = 4096 points, K = 256, one thread.

Not run by CI or `cargo bench`: it is the outside reference of issue 2's speed goal. Set-up and run
(PyPI has the wheel):

    python3 -m venv /tmp/fenv && /tmp/fenv/bin/pip install finufft==2.5.1 numpy
    OPENBLAS_NUM_THREADS=1 /tmp/fenv/bin/python benches/finufft_reference.py

FINUFFT's time depends on the process's memory layout: on the development machine 1.7 ms per set
as above, 3.0 ms when the same script runs with MALLOC_MMAP_THRESHOLD_=1073741824 (and the reverse
in other scripts; we did not find why). Quote the lower. Conventions as in DESIGN §3: F(k) = Σ exp(−2πi k·x),
k = −K/2 … K/2 − 1, P = |F|²/N; the error is the contract's (max relative error of P over bins at
least 1e-3 of the mean, against an exact DFT of the first set).
"""

import time

import finufft
import numpy as np

N, K, R, REPEATS = 4096, 256, 100, 5
rng = np.random.default_rng(1)
sets = 2 * np.pi * rng.random((R, 2, N))  # x, y in [0, 2π): FINUFFT's e^{-i k x} is our e^{-2πi k x}
ones = np.ones(N, dtype=np.complex128)
k = np.arange(-K // 2, K // 2)
exact = np.abs(np.exp(-1j * np.outer(k, sets[0, 0])) @ np.exp(-1j * np.outer(k, sets[0, 1])).T) ** 2 / N
band = exact >= 1e-3 * exact.mean()

print("eps, ms per set (best of %d runs of %d sets), contract error of P" % (REPEATS, R))
for eps in [1e-3, 1e-6, 1e-7, 3e-8, 1e-8, 1e-9]:
    plan = finufft.Plan(1, (K, K), n_trans=1, eps=eps, isign=-1, nthreads=1)
    out = np.empty((K, K), dtype=np.complex128)
    best = float("inf")
    for _ in range(REPEATS):
        t0 = time.process_time()
        for r in range(R):
            plan.setpts(sets[r, 0], sets[r, 1])
            plan.execute(ones, out=out)
        best = min(best, time.process_time() - t0)
    plan.setpts(sets[0, 0], sets[0, 1])
    p = np.abs(plan.execute(ones)) ** 2 / N
    err = np.max(np.abs(p[band] - exact[band]) / exact[band])
    print(f"{eps:g}, {best / R * 1e3:.3f}, {err:.2e}", flush=True)
