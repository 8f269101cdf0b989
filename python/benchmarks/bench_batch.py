"""Batched FK through Python vs the same loop in C++ (target: within 1.2x).

    python python/benchmarks/bench_batch.py --cpp build/python/bench_batch_cpp [--rows 100000]

Both sides solve FK of the default robot along the same smooth trajectory of `rows`
configurations, each warm-started from the previous one. The C++ side is
python/benchmarks/bench_batch_cpp.cpp (target bench_batch_cpp, not built by default).
"""
import argparse
import subprocess
import time

import numpy as np

import pcr


def trajectory(rows, n=3):
    k = np.arange(rows)[:, None]
    i = np.arange(n)[None, :]
    return 0.003 * np.sin(2.0 * np.pi * (i + 1) * k / rows + i)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=100000)
    parser.add_argument("--repeat", type=int, default=3, help="best of this many runs")
    parser.add_argument("--cpp", help="path of bench_batch_cpp (omit to time Python only)")
    args = parser.parse_args()

    robot = pcr.Robot.default()
    q = trajectory(args.rows)
    best_py = float("inf")
    for _ in range(args.repeat):
        start = time.perf_counter()
        result = robot.forward(q)
        best_py = min(best_py, time.perf_counter() - start)
    assert result.converged.all(), "some rows did not converge"
    print(f"python: {args.rows} FK in {best_py:.3f} s ({1e6 * best_py / args.rows:.2f} us each)")
    if args.cpp:
        best_cpp = float("inf")
        for _ in range(args.repeat):
            out = subprocess.run([args.cpp, str(args.rows)], capture_output=True, text=True,
                                 check=True).stdout.split()
            best_cpp = min(best_cpp, float(out[1]))
        print(f"c++:    {args.rows} FK in {best_cpp:.3f} s ({1e6 * best_cpp / args.rows:.2f} us each)")
        print(f"ratio python / c++: {best_py / best_cpp:.3f} (target <= 1.2)")


if __name__ == "__main__":
    main()
