"""A tolerance report on the terminal: per response its nominal value, first-order and Monte Carlo
mean and standard deviation and the spec (display units), and whether it is near linear (the
percentiles are in the report); the sources' ranked contributions; how Monte Carlo compares with first
order; the yield."""

from __future__ import annotations

from rich.console import Console

from flexmech.api.cli.common import number, shown, table_of
from flexmech.api.cli.quantities import row_texts


def print_tolerance(out: Console, report: dict) -> tuple[str, ...]:
    """The tables of a tolerance report (nothing for another analysis); the report's keys they show."""
    if report.get("analysis") != "tolerance":
        return ()
    responses = report.get("responses") or {}
    heads = ("response", "nominal", "std", "mean (MC)", "std (MC)", "spec", "linear")
    title = "responses: first order (its mean is the nominal value) and Monte Carlo (MC)"
    table = table_of(title, *heads, text=1)
    for name, entry in responses.items():
        table.add_row(shown(name), *map(shown, _row(entry)))
    out.print(table)
    contributions = table_of("contributions (first order), largest first", "response", "source", "per sigma", "share")
    for name, entry in responses.items():
        for c in entry["first_order"]["contributions"][:10]:
            source = c["source"] + (f" (+{len(c['fields']) - 1} with it)" if len(c["fields"]) > 1 else "")
            per_sigma = number(c["per_sigma"], entry["unit"])
            contributions.add_row(shown(name), shown(source), shown(per_sigma), f"{100 * c['share']:.1f} %")
    out.print(contributions)
    for name, entry in responses.items():
        out.print(f"{shown(name)}: {shown(entry['linearity']['verdict'])}")
        if "agreement" in (entry.get("monte_carlo") or {}):
            out.print(f"  Monte Carlo {shown(entry['monte_carlo']['agreement'])}")
    found = report.get("yield")
    if found:
        out.print(
            f"yield: {100 * found['monte_carlo']:.2f} % +- {100 * found['standard_error']:.2f} % of {found['samples']} "
            f"samples (the first-order model on the same samples: {100 * found['first_order']:.2f} %); "
            f"{found['failing']} failing"
        )
    return ("responses", "yield")


def _row(entry: dict) -> list[str]:
    unit, first, sampled = entry["unit"], entry["first_order"], entry.get("monte_carlo") or {}
    texts = row_texts([entry["nominal"], first["std"], sampled.get("mean"), sampled.get("std")], unit)
    spec = entry.get("spec") or {}
    bounds = [number(spec[k], unit) if spec.get(k) is not None else "" for k in ("min", "max")]
    texts.append(" .. ".join(bounds) if spec else "-")
    texts.append("near" if entry["linearity"]["near_linear"] else "no")
    return texts
