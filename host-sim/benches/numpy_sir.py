"""The numpy peer: the bootstrap SIR of `foxhunt perf`, written the way users write it today.

Same scenario (aoa-afsa: emitter (1200, 800) m, 60 bearings on a 300 m circle, sigma^2 =
3.801e-4 rad^2), same algorithm (1 m^2 jitter per step, Gaussian likelihood of the wrapped
residual, systematic resampling by filterpy after every step, weighted mean: the registry's
`sir-seed`), same initial cloud distribution (N(emitter, 50^2 I)). Prints one JSON object per
particle count.

Usage: python numpy_sir.py --runs R N [N ...]
"""

import argparse
import json
import time

import numpy as np
from filterpy.monte_carlo import systematic_resample

EMITTER = np.array([1200.0, 800.0])
SIGMA = np.sqrt(3.801e-4)
PROCESS_VAR = 1.0


def route():
    start = np.arctan2(-EMITTER[1], -EMITTER[0])
    a = start + 2.0 * np.pi * np.arange(60) / 60.0
    return EMITTER + 300.0 * np.stack([np.cos(a), np.sin(a)], axis=1)


def bearings(vehicles, rng):
    d = EMITTER - vehicles
    theta = np.arctan2(d[:, 1], d[:, 0]) + SIGMA * rng.standard_normal(len(vehicles))
    return np.angle(np.exp(1j * theta))


def sir(n, vehicles, theta, rng):
    particles = EMITTER + 50.0 * rng.standard_normal((n, 2))
    weights = np.full(n, 1.0 / n)
    for v, z in zip(vehicles, theta):
        particles += np.sqrt(PROCESS_VAR) * rng.standard_normal((n, 2))
        h = np.arctan2(particles[:, 1] - v[1], particles[:, 0] - v[0])
        r = np.angle(np.exp(1j * (z - h)))
        weights *= np.exp(-0.5 * (r / SIGMA) ** 2)
        weights += 1e-300
        weights /= weights.sum()
        estimate = np.average(particles, weights=weights, axis=0)
        idx = systematic_resample(weights)
        particles = particles[idx]
        weights.fill(1.0 / n)
    return estimate


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--runs", type=int, default=20)
    p.add_argument("n", type=int, nargs="+")
    a = p.parse_args()
    vehicles = route()
    for n in a.n:
        rng = np.random.default_rng(1)
        # One untimed run first (the Rust side does the same): first-call costs are not the
        # filter's.
        sir(n, vehicles, bearings(vehicles, rng), rng)
        sq, elapsed = 0.0, 0.0
        for _ in range(a.runs):
            theta = bearings(vehicles, rng)
            t = time.perf_counter()
            est = sir(n, vehicles, theta, rng)
            elapsed += time.perf_counter() - t
            sq += float(np.sum((est - EMITTER) ** 2))
        print(json.dumps({"particles": n, "runs": a.runs, "seconds_per_run": elapsed / a.runs,
                          "rmse": (sq / a.runs) ** 0.5}))


if __name__ == "__main__":
    main()
