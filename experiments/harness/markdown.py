"""Markdown for the studies' documents: a table, its rows and its "mean +- sd" cells."""

from __future__ import annotations


def line(*cells) -> str:
    """One markdown table row."""
    return "| " + " | ".join(str(c) for c in cells) + " |"


def head(*names) -> list[str]:
    """A markdown table's header row and its rule."""
    return [line(*names), "|" + "---|" * len(names)]


def table(names, rows) -> str:
    """A markdown table: its header, then a row per list of cells."""
    return "\n".join(head(*names) + [line(*row) for row in rows])


def mean_sd(mean: float, sd: float, digits: int = 3) -> str:
    """"mean +- sd", each to ``digits`` decimals."""
    return f"{mean:.{digits}f} +- {sd:.{digits}f}"
