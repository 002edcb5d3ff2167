"""The benchmark report (``report.md``) and the benchmark section of ``docs/benchmarks.md``.

Both are drawn from the saved raw results (:func:`benchmarks.suite.load`),
the charts already drawn from them (:mod:`benchmarks.charts`) and the saved
output of the speed step; nothing here measures anything.
"""

import math
import os
import re
import shutil
from pathlib import Path

from benchmarks import summary
from benchmarks.charts import CAPTIONS

#: The section of the published page that this module owns.
MARKERS = ("<!-- bench:start -->", "<!-- bench:end -->")

CHART_TITLES = {
    "accuracy_speed": "Accuracy against speed",
    "stability_triangle": "Stability sweeps: triangles",
    "stability_round": "Stability sweeps: disks and circles",
    "tessellation": "Tessellation: error and cost against K",
}


def num(x):
    """Three significant digits, exponents written short: ``6.43e7``, ``0.828``, ``2.1e-5``."""
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    if math.isinf(x):
        return "> 1.8e308" if x > 0 else "-inf"
    if x == 0:
        return "0"
    text = f"{x:.3g}"
    return re.sub(r"e([+-])0*(\d)", lambda m: "e" + ("-" if m.group(1) == "-" else "") + m.group(2), text)


def _failed(s):
    if not s.failed:
        return "0"
    return summary.failure_text(s.failures, s.n)


def summary_table(raw):
    """Markdown: per query type and entity, speed, errors, failures."""
    lines = [
        "| query | method / backend | queries/s | worst (eps·S) | median (eps·S) "
        "| worst relative (d* > 0) | median relative (d* > 0) | worst where d* = 0 (eps·S) "
        "| failed | beyond bound |",
        "|---|---|---:|---:|---:|---:|---:|---:|---|---:|",
    ]
    for kind in summary.KINDS:
        kinds = dict(summary.entities(raw, kind))
        for name, s in summary.by_kind(raw, kind).items():
            label = f"`{name}`" if kinds[name] == "method" else name
            lines.append(
                f"| point–{kind} | {label} | {num(s.qps)} | {num(s.worst['error_eps_s'])} "
                f"| {num(s.median['error_eps_s'])} | {num(s.worst['error_relative'])} "
                f"| {num(s.median['error_relative'])} | {num(s.on_shape_worst)} | {_failed(s)} | {s.beyond} |"
            )
    return "\n".join(lines)


def _provenance(raw, commit=True):
    """Where and how the run was made; ``commit``: with the commit it ran at (the
    report), or without (the published page, whose figures stand for the code as it is)."""
    meta = raw["meta"]
    machine, versions, cfg = meta["machine"], meta["versions"], meta["config"]
    load = machine.get("load_average") or {}
    libraries = ", ".join(
        dict.fromkeys(
            str(v) for k, v in versions.items() if k not in ("proximity", "commit", "numpy", "numba") and v
        )
    )
    commit = f" at commit {versions['commit']}" if commit and versions.get("commit") else ""
    return (
        f"`{meta['command']}` on {meta['date'][:10]}: {machine['cpu']}, {machine['cores']} cores "
        f"(load average {load.get('before', '?')} before, {load.get('after', '?')} after), "
        f"Python {machine['python']}, NumPy {versions['numpy']}, numba {versions['numba']}; "
        f"proximity {versions['proximity']}{commit}; {libraries}.  Seed {cfg['seed']}, "
        f"{cfg['n_accuracy']} queries per family for accuracy; the suite took "
        f"{meta['wall_seconds']:.0f} s."
    )


METHOD_NOTES = """\
* **Errors** are `|d - d*|` against the exact reference (`proximity.testing.exact`: rational arithmetic on the
  floats' exact values), in two units: `eps·S`, with `eps = 2^-52 ≈ 2.2e-16` and `S = max_i |P - V_i|` for
  triangles or `|P - C| + R` for disks and circles, the query's size (`robust` promises at most 8: an
  error of a few units in the 16th digit of the query's size), and relative to the distance,
  `|d - d*| / d*`, over the queries with `d* > 0` (`certified` promises one ulp of `d*`, at most
  `2.2e-16` of it; `robust`'s bound is on the size, so for a point very close to the shape its
  relative error can be large while its error in `eps·S` stays below 8).  Where `d* = 0` (the point
  is on the shape) there is no relative error; those queries have their own column, in `eps·S`.
* **Statistics are over the answered queries.**  Queries without an answer are counted by reason
  instead: NaN, inf or an exception for proximity's methods; the adapters' failure codes for the
  libraries (`docs/adapters.md`): no result, sentinel, false touching, point off the shape,
  inconsistent.
* **Beyond bound** counts answered queries whose error exceeds the method's bound ({bounds}; `eberly`
  makes no promise and is counted against `robust`'s), or the backend's documented tolerance.
* **Queries per second**: `closest_point`, the median of {repeats} timed repeats, then the median
  over families.  proximity's methods get batches of up to {batch} queries (fewer where a method is
  slow, so that a repeat takes about {method_seconds:g} s).  The libraries are asked
  through the adapters: each call builds the library's model of every shape, and these scenes have
  one shape per query, so the time includes model building and the adapters' translation (which
  calls proximity, on one thread); they get as many queries as fill about {target:g} s.
* Disks and circles are tessellated by fcl (circles), trimesh (both) and pybullet (circles) with
  the adapters' default tolerance, `1e-3 R`: their errors of about `1e12 eps·S` are that modelling
  error, not rounding (see the tessellation chart).
"""


def _bounds(raw):
    """``"`robust`: 8 eps S, `certified`: 1 ulp of d*"`` from the records."""
    bounds = {}
    for family in raw["families"]:
        for name, record in family["results"].items():
            if record.get("bound") and record["bound"] != "documented tolerance":
                bounds.setdefault(name, record["bound"])
    return ", ".join(f"`{name}`: {bound}" for name, bound in bounds.items() if name != "eberly")


def diagnostics(raw):
    """Markdown lines: each method's counters (``extra``) summed per query type, with the top families."""
    lines = []
    for kind in summary.KINDS:
        totals, per_family = {}, {}
        for family in summary.families(raw, kind):
            for name, record in family["results"].items():
                for key, value in (record.get("extra") or {}).items():
                    totals.setdefault(name, {}).setdefault(key, 0)
                    totals[name][key] += value
                    per_family.setdefault((name, key), []).append((value, family["family"]))
        for name, counts in totals.items():
            text = ", ".join(f"{key} {value}" for key, value in counts.items())
            top = []
            for key in counts:
                ranked = sorted(per_family[(name, key)], reverse=True)[:3]
                if key != "queries" and ranked and ranked[0][0]:
                    top.append(f"most {key} in " + ", ".join(f"{label} ({v})" for v, label in ranked if v))
            lines.append(f"* point–{kind}, `{name}`: {text}" + (f"; {'; '.join(top)}" if top else ""))
    return lines


def _families_text(records, registry):
    """Family records grouped by generator: ``"sliver (1e-09, 1e-17), degenerate (all)"``.

    ``registry`` holds every family record of the query type, to say "all".
    """
    groups = {}
    for family in records:
        groups.setdefault(family["name"], []).append(family)
    parts = []
    for name, members in groups.items():
        total = sum(1 for f in registry if f["name"] == name)
        if not members[0]["params"]:
            parts.append(name)
        elif len(members) == total:
            parts.append(f"{name} (all)")
        else:
            values = [next(iter(f["params"].values())) for f in members]
            parts.append(f"{name} (" + ", ".join(v if isinstance(v, str) else f"{v:g}" for v in values) + ")")
    return ", ".join(parts)


def where_they_fail(raw):
    """Markdown bullets: for each entity, the families where it leaves queries unanswered
    and those where its answers break its bound, grouped by generator."""
    lines = []
    for kind in summary.KINDS:
        registry = summary.families(raw, kind)
        rows = summary.by_family(raw, kind)
        for name, total in summary.by_kind(raw, kind).items():
            failing = [f for f, stats in rows if stats[name].failed]
            beyond = [f for f, stats in rows if stats[name].beyond]
            if not failing and not beyond:
                continue
            text = []
            if failing:
                text.append(
                    f"no answer to {_failed(total)} of the queries, in {_families_text(failing, registry)}"
                )
            if beyond:
                text.append(f"{total.beyond} answers beyond its bound, in {_families_text(beyond, registry)}")
            lines.append(f"* point–{kind}, `{name}`: " + "; ".join(text) + ".")
    return lines


def _family_tables(raw, kind):
    rows = summary.by_family(raw, kind)
    if not rows:
        return ""
    names = list(rows[0][1])
    head = "| family | " + " | ".join(f"`{n}`" for n in names) + " |"
    lines = [head, "|---|" + "---:|" * len(names)]
    for family, stats in rows:
        cells = []
        for name in names:
            s = stats[name]
            cell = num(s.worst["error_eps_s"]) if s.answered else "–"
            if s.failed:
                reasons = ", ".join(
                    f"{count} {summary.REASONS.get(reason, reason)}"
                    for reason, count in sorted(s.failures.items())
                )
                cell = f"{cell} ({reasons})" if s.answered else reasons
            cells.append(cell)
        lines.append(f"| {family['family']} | " + " | ".join(cells) + " |")
    speed = ["| family | " + " | ".join(f"`{n}`" for n in names) + " |", "|---|" + "---:|" * len(names)]
    for family, stats in rows:
        speed.append(f"| {family['family']} | " + " | ".join(num(stats[n].qps) for n in names) + " |")
    return (
        f"#### point–{kind}: worst error (eps·S) and failures\n\n"
        + "\n".join(lines)
        + f"\n\n#### point–{kind}: queries per second\n\n"
        + "\n".join(speed)
        + "\n"
    )


def _tessellation_table(raw):
    records = [r for r in raw.get("tessellation", []) if r.get("segments")]
    if not records:
        return ""
    lines = [
        "| query | backend | K | sagitta bound | worst error | median error | µs per query |",
        "|---|---|---:|---:|---:|---:|---:|",
    ]
    for r in records:
        if r.get("skipped"):
            lines.append(f"| point–{r['kind']} | {r['entity']} | {r['segments']} | | | | {r['skipped']} |")
            continue
        errors = sorted(e for e in r["error"] if e is not None)
        worst = errors[-1] if errors else math.nan
        median = errors[len(errors) // 2] if errors else math.nan
        lines.append(
            f"| point–{r['kind']} | {r['entity']} | {r['segments']} | {num(r['bound'])} | {num(worst)} "
            f"| {num(median)} | {num(1e6 / r['timing']['qps'])} |"
        )
    n = records[0]["n"]
    return (
        f"Radius 1, {n} queries per K (`disk_well_conditioned` scaled to R = 1).\n\n"
        + "\n".join(lines)
        + "\n"
    )


def render(raw, charts, speed_text=None, pairs_text=None):
    """The text of ``report.md``; ``pairs_text``: the section of the primitive pairs' stability
    sweeps (:func:`benchmarks.pair_stability.markdown`), if they were run."""
    cfg = raw["meta"]["config"]
    parts = [
        "# Benchmark report",
        "",
        _provenance(raw),
        "",
        "## Summary",
        "",
        "Errors and failures over every scene family of `proximity/testing/scenes.py` "
        f"({len(summary.families(raw, 'triangle'))} triangle families, "
        f"{len(summary.families(raw, 'disk'))} disk and circle families).",
        "",
        summary_table(raw),
        "",
        METHOD_NOTES.format(
            repeats=cfg["repeats"],
            batch=cfg["batch"],
            target=cfg["target_seconds"],
            method_seconds=cfg["method_seconds"],
            bounds=_bounds(raw),
        ),
        "## Charts",
        "",
    ]
    for name, path in charts.items():
        parts += [
            f"### {CHART_TITLES.get(name, name)}",
            "",
            f"![{CHART_TITLES.get(name, name)}]({Path(path).name})",
            "",
            CAPTIONS.get(name, ""),
            "",
        ]
    parts += ["## Where each one fails", "", *where_they_fail(raw)]
    counters = diagnostics(raw)
    if counters:
        parts += ["", "## Method counters", "", "Counted over the accuracy batches.", "", *counters]
    parts += ["", "## By family", ""]
    for kind in summary.KINDS:
        parts += [_family_tables(raw, kind)]
    parts += ["## Tessellation", "", _tessellation_table(raw)]
    if pairs_text is not None:
        parts += ["## Stability of the primitive pairs (`benchmarks.pair_stability`)", "", pairs_text]
    if speed_text is not None:
        parts += ["## Speed comparison (`benchmarks.speed`)", "", "```text", speed_text.rstrip(), "```", ""]
    return "\n".join(parts)


def write(raw, out, charts, speed_path=None, pairs_text=None):
    """Write ``out/report.md``; ``speed_path`` is the saved output of the speed step, if any;
    ``pairs_text`` as in :func:`render`."""
    speed_text = Path(speed_path).read_text(encoding="utf-8") if speed_path else None
    path = Path(out) / "report.md"
    path.write_text(render(raw, charts, speed_text, pairs_text), encoding="utf-8")
    return path


def page_section(raw, charts, images=""):
    """The benchmark section of the published page (between the markers), from the saved data.

    ``images`` is the charts' directory relative to the page, ending in ``/`` (or empty).
    """
    figures = "\n\n".join(
        f"![{CHART_TITLES.get(name, name)}]({images}{Path(path).name})\n\n{CAPTIONS.get(name, '')}"
        for name, path in charts.items()
    )
    return f"""\
The numbers below: {_provenance(raw, commit=False)}

{summary_table(raw)}

Errors are over the answered queries, in units of `eps·S` (`eps = 2^-52`, `S` the query's size;
robust's bound is 8) and relative to the exact distance `d*` over the queries with `d* > 0`
(certified's bound is one ulp of `d*`, at most 2.2e-16 of it); where `d* = 0` (the point is on the
shape) there is no relative error, so those queries have their own column in `eps·S`.  Unanswered queries are
counted under "failed", by reason.  "Beyond bound" counts answers outside the method's bound
({_bounds(raw)}; `eberly`, which promises nothing, against `robust`'s) or outside the backend's
documented tolerance.  The libraries are timed through the adapters, which build a model per shape
(one per query here); disks and circles they tessellate are off by the modelling error.

Where each one fails (families grouped by generator, with the swept values):

{chr(10).join(where_they_fail(raw))}

## Charts

{figures}
"""


def publish(raw, charts, docs, page):
    """Copy the charts to ``docs`` and rewrite the section between the bench markers of ``page``."""
    docs, page = Path(docs), Path(page)
    docs.mkdir(parents=True, exist_ok=True)
    for path in charts.values():
        shutil.copyfile(path, docs / Path(path).name)
    text = page.read_text(encoding="utf-8")
    start, end = MARKERS
    pattern = re.compile(re.escape(start) + r"\n.*?" + re.escape(end), re.S)
    if not pattern.search(text):
        raise SystemExit(f"{page} has no {start} ... {end} markers")
    relative = Path(os.path.relpath(docs, page.parent)).as_posix()
    section = page_section(raw, charts, images="" if relative == "." else f"{relative}/")
    page.write_text(pattern.sub(lambda m: f"{start}\n{section}{end}", text, count=1), encoding="utf-8")
