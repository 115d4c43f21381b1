"""Variance, cost and efficiency of the g(E[X]) estimators; writes the "estimators" section of
BENCHMARKS.md.

For each target g (I^k for k = 2..8, gamma I^(1/2.2), exp(I), 1/I, tie-dye) and each applicable
estimator, many independent estimates are drawn from one known distribution of X, and we report:
variance, measured mean samples per estimate (draw() calls), measured bias +- standard error, and
efficiency 1 / (MSE x samples) relative to a named baseline (naive products where they exist). It
also checks U-statistic <= naive variance at equal sample counts, measures float32 (Dr.Jit kernel)
against float64 (numpy), and plots error versus samples to docs/estimators_error.png.

Run: .venv/bin/python benchmarks/estimators_table.py   (about a minute on 2 cores)
"""
from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np
from _report import machine_description, write_section

import styletrace.estimators as E

ROOT = Path(__file__).resolve().parents[1]

LANES = 100_000
DIST = E.Uniform(0.2, 1.0)  # X ~ U(0.2, 1.0): I = 0.6, Var X = 0.0533
I = DIST.mean
RNG_SEED = 2024


def measure(est, exact, seed, dist=DIST, channels=None, lanes=LANES):
    r = E.estimate_numpy(est, dist, lanes, np.random.default_rng(seed), channels=channels)
    v = r.values.reshape(lanes, -1)
    var = float(np.mean(v.var(axis=0, ddof=1)))  # mean over channels
    bias = float(np.mean(v.mean(axis=0) - np.atleast_1d(exact)))
    se = float(np.sqrt(np.mean(v.var(axis=0, ddof=1)) / lanes))
    return {"name": est.name, "samples": float(r.draws.mean()), "var": var, "bias": bias, "se": se,
            "expected_samples": est.mean_draws}


def efficiency(row, base):
    """1 / (MSE x samples), MSE = var + bias^2 for biased rows (bias counted only when
    resolvable)."""
    def cost(r):
        b2 = r["bias"] ** 2 if abs(r["bias"]) > 4 * r["se"] else 0.0
        return (r["var"] + b2) * r["samples"]
    return cost(base) / cost(row)


def fmt_row(label, row, base, biased=False):
    bias = f"{row['bias']:+.2e} ± {row['se']:.1e}"
    mark = " (MSE)" if biased else ""
    return (f"| {label} | {row['samples']:.2f} | {row['var']:.3e} | {bias} | "
            f"{efficiency(row, base):.3g}{mark} |")


HEADER = ("| estimator | samples / estimate | variance | bias ± s.e. | efficiency |\n"
          "|---|---:|---:|---:|---:|")


def series_plans(series, b):
    return [
        (
            "series single-term, Poisson(2)",
            E.SeriesEstimator(series, b=b, selection="single", truncation=E.Poisson(2.0)),
        ),
        (
            "series iterative, Poisson-CMF(2), U-stat terms",
            E.SeriesEstimator(
                series, b=b, selection="iterative", truncation=E.PoissonCMF(2.0), terms="ustat"
            ),
        ),
        (
            "series iterative, Poisson-CMF(2), naive terms",
            E.SeriesEstimator(
                series, b=b, selection="iterative", truncation=E.PoissonCMF(2.0), terms="naive"
            ),
        ),
        (
            "series recursive (roulette), cumulative",
            E.SeriesEstimator(series, b=b, selection="recursive", truncation=E.Cumulative()),
        ),
        (
            "series recursive (roulette), Poisson-CMF(2)",
            E.SeriesEstimator(series, b=b, selection="recursive", truncation=E.PoissonCMF(2.0)),
        ),
        (
            "series iterative, Poisson-CMF(1), U-stat terms",
            E.SeriesEstimator(
                series, b=b, selection="iterative", truncation=E.PoissonCMF(1.0), terms="ustat"
            ),
        ),
    ]


def powers_section(seed):
    lines = [
        "### I^k (k = 2..8)",
        "",
        "Baseline: the naive product of k samples (S6). U-stat(n) averages all k-subsets of n "
        "samples; "
        "\"naive x2\" is the mean of two independent naive products (2k samples, the U-statistic's "
        "equal-count competitor); direct(n) = g(mean of n) is biased, so its efficiency uses MSE.",
        "",
        "| k | estimator | samples / estimate | variance | bias ± s.e. | efficiency |",
        "|---|---|---:|---:|---:|---:|",
    ]
    ustat_check = [
        "| k | n | U-stat variance | naive (n/k products) variance | difference / s.e. |",
        "|---|---:|---:|---:|---:|",
    ]
    for k in range(2, 9):
        coeffs = [0.0] * k + [1.0]
        exact = I ** k
        base = measure(E.PolynomialNaive(coeffs), exact, seed + k)
        rows = [("naive (S6)", base, False)]
        u2 = measure(E.PolynomialU(coeffs, n=2 * k), exact, seed + 100 + k)
        rows.append((f"U-stat n={2 * k}", u2, False))
        rows.append(
            (
                f"U-stat n={4 * k}",
                measure(E.PolynomialU(coeffs, n=4 * k), exact, seed + 200 + k),
                False,
            )
        )
        n1 = E.estimate_numpy(
            E.PolynomialNaive(coeffs), DIST, LANES, np.random.default_rng(seed + 300 + k)
        ).values
        n2 = E.estimate_numpy(
            E.PolynomialNaive(coeffs), DIST, LANES, np.random.default_rng(seed + 400 + k)
        ).values
        nx2 = (n1 + n2) / 2
        naive2 = {
            "samples": 2.0 * k,
            "var": float(nx2.var(ddof=1)),
            "bias": float(nx2.mean() - exact),
            "se": float(nx2.std(ddof=1) / math.sqrt(LANES)),
        }
        rows.append(("naive x2 (mean of 2)", naive2, False))
        rows.append(
            (
                f"direct n={k}",
                measure(E.Direct(lambda x, k=k: x**k, k), exact, seed + 500 + k),
                True,
            )
        )
        for label, row, biased in rows:
            lines.append(f"| {k} " + fmt_row(label, row, base, biased))
        # U <= naive at equal sample count (2k), with the standard error of the variance difference
        u = E.estimate_numpy(
            E.PolynomialU(coeffs, n=2 * k), DIST, LANES, np.random.default_rng(seed + 600 + k)
        ).values
        se_u = math.sqrt(np.var((u - u.mean()) ** 2) / LANES)
        se_n = math.sqrt(np.var((nx2 - nx2.mean()) ** 2) / LANES)
        d = (naive2["var"] - u.var(ddof=1)) / math.hypot(se_u, se_n)
        ustat_check.append(
            f"| {k} | {2 * k} | {u.var(ddof=1):.3e} | {naive2['var']:.3e} | {d:+.1f} |"
        )
    return lines, ustat_check


def series_section(title, series, exact, b, seed, direct_g, extra=()):
    lines = [
        f"### {title}",
        "",
        "Baseline: iterative prefix-sum with Poisson-CMF(2) and naive term estimates (products of "
        "samples, S6): the naive estimator of a truncated infinite series (there is no fixed-cost "
        "naive "
        f"estimator of an infinite series). Expansion point: {b!r}.",
        "",
        HEADER,
    ]
    rows = []
    for i, (label, est) in enumerate(series_plans(series, b)):
        rows.append((label, measure(est, exact, seed + i), False))
    for j, (label, est) in enumerate(extra):
        rows.append((label, measure(est, exact, seed + 50 + j), False))
    tel = E.Telescoping(direct_g, n0=4)
    rows.append((f"telescoping n0=4, {tel.truncation.name}", measure(tel, exact, seed + 80), False))
    for n in (1, 8):
        rows.append((f"direct n={n}", measure(E.Direct(direct_g, n), exact, seed + 90 + n), True))
    base = rows[2][1]
    lines += [fmt_row(label + (" (baseline)" if i == 2 else ""), row, base, biased)
              for i, (label, row, biased) in enumerate(rows)]
    return lines, rows


def tie_dye_section(seed):
    fit = E.tie_dye_fit()
    dist = E.Uniform(0.2, 1.0)  # channels x, 2x, 3x: I = (0.6, 1.2, 1.8), all inside [-1, 4]
    Ic = E.channel_means(dist, 3)
    exact = fit(Ic)
    true = E.tie_dye(Ic)
    lines = [
        "### Tie-dye (degree-20 Chebyshev fit on [-1, 4], per channel)",
        "",
        "X ~ U(0.2, 1.0) scaled per channel by (1, 2, 3), so I = (0.6, 1.2, 1.8). Unbiased rows "
        "are "
        "measured against the fit h(I); the fit itself differs from tie-dye(I) by "
        f"{np.array2string(exact - true, precision=4)} here (max fit error on [-1, 4]: "
        f"{np.array2string(fit.max_error(list(E.TIE_DYE)), precision=4)}). Variance is the mean "
        f"over channels. "
        "Baseline: naive products about the interval center b = 1.5 (20 samples).",
        "",
        HEADER,
    ]
    ests = [
        ("naive (S6), b = 1.5", E.PolynomialNaive(fit)),
        ("naive, b = pilot(1)", E.PolynomialNaive(fit, b=E.Pilot(1))),
        ("U-stat n=20, b = 1.5", E.PolynomialU(fit, n=20)),
        ("U-stat n=20, b = pilot(1)", E.PolynomialU(fit, n=20, b=E.Pilot(1))),
        ("U-stat n=40, b = pilot(1)", E.PolynomialU(fit, n=40, b=E.Pilot(1))),
        (
            "series iterative, Poisson-CMF(2), U-stat, b = pilot(1)",
            E.SeriesEstimator(
                fit, b=E.Pilot(1), selection="iterative", truncation=E.PoissonCMF(2.0)
            ),
        ),
        (
            "series recursive, cumulative(min 0.01), b = pilot(1)",
            E.SeriesEstimator(
                fit, b=E.Pilot(1), selection="recursive", truncation=E.Cumulative(0.01)
            ),
        ),
    ]
    rows = [(label, measure(est, exact, seed + i, dist=dist, channels=3, lanes=50_000), False)
            for i, (label, est) in enumerate(ests)]
    for n in (8, 20):
        rows.append(
            (
                f"direct n={n} (vs h(I))",
                measure(
                    E.Direct(E.tie_dye, n),
                    exact,
                    seed + 70 + n,
                    dist=dist,
                    channels=3,
                    lanes=50_000,
                ),
                True,
            )
        )
    base = rows[0][1]
    lines += [fmt_row(label, row, base, biased) for label, row, biased in rows]
    return lines


def float32_section(seed):
    """The same estimators in a float32 Dr.Jit kernel versus float64 numpy."""
    try:
        from styletrace.jit import prepare_drjit
        prepare_drjit()  # a working libLLVM first; estimate_drjit follows the backend it picks
    except Exception as exc:  # pragma: no cover - reported in the table instead
        return [f"(Dr.Jit unavailable: {exc})"]
    fit = E.tie_dye_fit()
    cases = [
        (
            "gamma 1/2.2, iterative U-stat, pilot b",
            E.SeriesEstimator(E.gamma_series(2.2, lo=0.2, hi=3.0), b=E.Pilot(1)),
            lambda I: I ** (1 / 2.2),
            E.Uniform(0.2, 1.0),
        ),
        (
            "tie-dye fit, U-stat n=20, pilot b",
            E.PolynomialU(fit, n=20, b=E.Pilot(1)),
            fit,
            E.Uniform(0.2, 1.0),
        ),
        (
            "tie-dye fit, U-stat n=20, pilot b, narrow X",
            E.PolynomialU(fit, n=20, b=E.Pilot(1)),
            fit,
            E.Uniform(0.5, 0.7),
        ),
    ]
    lines = ["| case | float32 kernel bias ± s.e. | float64 numpy bias ± s.e. |", "|---|---:|---:|"]
    for i, (label, est, g, dist) in enumerate(cases):
        exact = g(E.channel_means(dist, 3))
        out = []
        for backend in ("drjit", "numpy"):
            if backend == "drjit":
                r = E.estimate_drjit(est, dist, 200_000, seed=seed + i, channels=3)
            else:
                r = E.estimate_numpy(
                    est, dist, 200_000, np.random.default_rng(seed + i), channels=3
                )
            d = r.values.mean(axis=0) - exact
            se = r.values.std(axis=0, ddof=1) / math.sqrt(len(r.values))
            k = int(np.argmax(np.abs(d) / se))
            out.append(f"{d[k]:+.2e} ± {se[k]:.1e} (channel {'rgb'[k]})")
        lines.append(f"| {label} | {out[0]} | {out[1]} |")
    # the monomial form itself: Horner about the centre b = 1.5, float32 versus float64 arithmetic
    x = np.linspace(-1.0, 4.0, 5001)
    X = np.stack([x, x, x], -1)
    s = fit.series()
    err = np.max(np.abs(s(X.astype(np.float32)) - s(X)), axis=0)
    cheb = np.max(np.abs(fit(X.astype(np.float32)) - fit(X)), axis=0)
    lines += [
        "",
        "Evaluating the degree-20 tie-dye fit in its monomial form sum c_k (x - 1.5)^k with "
        "float32 arithmetic on [-1, 4] (no sampling): max error "
        f"{np.array2string(err, precision=3)} per channel; "
        "the Chebyshev recurrence fit(x) in float32: "
        f"{np.array2string(cheb, precision=3)}.",
    ]
    return lines


def error_plot(path, seed):
    """RMSE of a pixel value versus total draw() calls: averaging independent estimates (spp)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    budgets = np.array([4, 8, 16, 32, 64, 128, 256, 512, 1024])
    fig, axes = plt.subplots(1, 2, figsize=(11.5, 4.4))
    targets = [
        (
            "gamma $I^{1/2.2}$",
            lambda x: np.maximum(x, 0) ** (1 / 2.2),
            E.gamma_series(2.2, lo=0.2, hi=1.0),
            None,
        ),
        ("$I^4$", lambda x: x**4, None, [0.0] * 4 + [1.0]),
    ]
    for ax, (title, g, series, coeffs) in zip(axes, targets):
        exact = g(I)
        for n, style in ((4, "o-"), (16, "o-")):
            v = E.estimate_numpy(
                E.Direct(g, n), DIST, 100_000, np.random.default_rng(seed + n)
            ).values
            bias, var = float(v.mean() - exact), float(v.var(ddof=1))
            N = budgets[budgets >= n]
            ax.loglog(
                N,
                np.sqrt(bias**2 + var * n / N),
                style,
                label=f"direct, n={n} per estimate, averaged",
            )
        one = []
        for n in budgets:
            v = E.estimate_numpy(
                E.Direct(g, int(n)), DIST, 20_000, np.random.default_rng(seed + 100 + int(n))
            ).values
            one.append(math.sqrt(np.mean((v - exact) ** 2)))
        ax.loglog(budgets, one, "k:", label="direct, all N samples in one estimate")
        if series is not None:
            plans = series_plans(series, E.Pilot(1))
            unbiased = [
                ("single-term Poisson(2)", plans[0][1]),
                ("iterative U-stat Poisson-CMF(2)", plans[1][1]),
                ("iterative naive Poisson-CMF(2)", plans[2][1]),
                ("recursive cumulative", plans[3][1]),
            ]
        else:
            unbiased = [("naive products (S6)", E.PolynomialNaive(coeffs)),
                        ("U-stat n=8", E.PolynomialU(coeffs, n=8)),
                        ("U-stat n=32", E.PolynomialU(coeffs, n=32))]
        for label, est in unbiased:
            r = E.estimate_numpy(est, DIST, 100_000, np.random.default_rng(seed + 7))
            var, ms = float(r.values.var(ddof=1)), float(r.draws.mean())
            N = budgets[budgets >= ms]
            ax.loglog(N, np.sqrt(var * ms / N), "s--", label=f"{label}, averaged (unbiased)")
        ax.set_title(f"{title}, X ~ U(0.2, 1.0)")
        ax.set_xlabel("total draw() calls for the pixel value (estimates x samples each)")
        ax.set_ylabel("RMSE")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=6.5)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    t0 = time.time()
    seed = RNG_SEED
    powers, ustat_check = powers_section(seed)
    gamma, _ = series_section(
        "Gamma I^(1/2.2) (power series, Eq. 24)",
        E.gamma_series(2.2, lo=0.2, hi=1.0),
        I ** (1 / 2.2),
        E.Pilot(1),
        seed + 1000,
        lambda x: x ** (1 / 2.2),
    )
    expo, _ = series_section(
        "exp(I) (S15)",
        E.exp_series(),
        math.exp(I),
        E.Pilot(1),
        seed + 2000,
        np.exp,
        extra=[
            (
                "series iterative, Poisson-CMF(2), U-stat, fixed b = 0.5",
                E.SeriesEstimator(E.exp_series(), b=0.5),
            )
        ],
    )
    recip, _ = series_section(
        "Reciprocal 1/I (S17), known range [0.2, 1.0]",
        E.reciprocal_series(1.0, lo=0.2, hi=1.0),
        1 / I,
        E.Pilot(1),
        seed + 3000,
        lambda x: 1.0 / x,
    )
    tie = tie_dye_section(seed + 4000)
    f32 = float32_section(seed + 5000)
    error_plot(ROOT / "docs" / "estimators_error.png", seed + 6000)
    elapsed = time.time() - t0

    body = "\n".join(
        [
            "## Estimators of g(E[X])",
            "",
            "Written by `benchmarks/estimators_table.py`. " + machine_description() + ".",
            "",
            f"Test distribution: X ~ Uniform(0.2, 1.0), so I = {I} and Var X = {DIST.var:.4f} "
            f"(tie-dye: per-channel "
            f"scaling, see below). {LANES:,} independent estimates per row (tie-dye 50,000), "
            f"numpy float64. "
            "Samples = measured mean draw() calls per estimate. Efficiency = 1 / (MSE x samples) "
            "relative to the "
            "row named as baseline (MSE = variance + bias^2, the bias counted only when it "
            "exceeds 4 standard "
            "errors; unbiased rows use their variance). Pilot = expansion point from one separate "
            "sample.",
            "",
            *powers,
            "",
            "U-statistic versus naive at equal sample count (2k samples each; positive = naive "
            "variance larger, in "
            "standard errors of the difference):",
            "",
            *ustat_check,
            "",
            *gamma,
            "",
            *expo,
            "",
            *recip,
            "",
            *tie,
            "",
            "### float32 kernel (Dr.Jit LLVM) versus float64 (numpy)",
            "",
            "Largest per-channel bias of 200,000 estimates; X ~ U(0.2, 1.0) unless said, channels "
            "x (1, 2, 3).",
            "",
            *f32,
            "",
            "Error versus samples: `docs/estimators_error.png`.",
            "",
            f"Script runtime: {elapsed:.0f} s.",
        ]
    )
    write_section("estimators", body)
    print(body)


if __name__ == "__main__":
    main()
