"""Worst error per scene family, for each method, against the exact reference.

Errors are in units of ``eps * S`` (``eps = 2^-52``; ``S = max_i |P - V_i|``
for triangles, ``|P - C| + R`` for circles and disks), the unit of the
robust method's bound of 8.

    python -m benchmarks.accuracy [-n 200] [--seed 0] [--write docs/accuracy.md]

With ``--write`` the table between the ``accuracy-table`` markers of that
file is replaced by the new one.
"""

import argparse
import math
import re
from dataclasses import dataclass

import numpy as np

from proximity.testing import scenes
from proximity.testing.accuracy import errors, reference, shape_of, ulp_errors  # noqa: F401

METHODS = ("eberly", "robust")


@dataclass(frozen=True)
class Accuracy:
    """Errors of one method on one family, in units of ``eps * S``."""

    worst: float
    median: float
    nan: int
    inf: int
    n: int


def measure(kind, family, n, seed, methods=METHODS):
    """``{method: Accuracy}`` for ``n`` queries of ``family`` (seeded)."""
    scene = family(np.random.default_rng(seed), n)
    shape = shape_of(kind, scene)
    ref = reference(kind, scene)
    out = {}
    for method in methods:
        d = shape.distance(scene.points, method=method)
        err = errors(d, ref)
        finite = err[np.isfinite(err)]
        out[method] = Accuracy(
            worst=float(err.max()) if len(err) else 0.0,
            median=float(np.median(finite)) if len(finite) else math.nan,
            nan=int(np.isnan(d).sum()),
            inf=int(np.isinf(d).sum()),
            n=len(d),
        )
    return out


def _cell(acc):
    worst = "fails" if not math.isfinite(acc.worst) else f"{acc.worst:.3g}"
    failures = []
    if acc.nan:
        failures.append(f"{acc.nan} NaN")
    if acc.inf:
        failures.append(f"{acc.inf} inf")
    if failures and math.isfinite(acc.worst):
        worst += f" ({', '.join(failures)})"
    elif failures:
        worst = ", ".join(failures)
    return worst


def table(n=200, seed=0):
    """The markdown table of worst errors for every family and shape kind."""
    lines = [
        "| shape | family | " + " | ".join(f"`{m}` worst" for m in METHODS) + " |",
        "|---|---|" + "---:|" * len(METHODS),
    ]
    groups = [
        ("triangle", scenes.TRIANGLE_FAMILIES),
        ("disk", scenes.DISK_FAMILIES),
        ("circle", scenes.DISK_FAMILIES),
    ]
    for kind, families in groups:
        for family in families:
            result = measure(kind, family, n, seed)
            cells = " | ".join(_cell(result[m]) for m in METHODS)
            lines.append(f"| {kind} | {family.label} | {cells} |")
    return "\n".join(lines)


def write_table(path, text):
    """Replace the table between the accuracy-table markers of ``path``."""
    with open(path, encoding="utf-8") as f:
        page = f.read()
    pattern = re.compile(r"(<!-- accuracy-table:start[^>]*-->\n).*?(<!-- accuracy-table:end -->)", re.S)
    if not pattern.search(page):
        raise SystemExit(f"{path} has no accuracy-table markers")
    with open(path, "w", encoding="utf-8") as f:
        f.write(pattern.sub(lambda m: m.group(1) + text + "\n" + m.group(2), page))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-n", type=int, default=200, help="queries per family (default 200)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--write", metavar="PATH", help="rewrite the table between the markers of this page")
    args = parser.parse_args(argv)
    text = table(args.n, args.seed)
    print(text)
    if args.write:
        write_table(args.write, text)


if __name__ == "__main__":
    main()
