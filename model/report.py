"""The paper's table as text (percentages of used and unused object-queries per method), and the F1 table."""

from __future__ import annotations


def format_table(result: dict) -> str:
    """The main table as markdown: percentages averaged over households (spread over households in brackets)."""
    lines = [f"window {result['window_min']} min, households: {', '.join(result['households'])}", "",
             "| method | used correct | used wrong | used missed | unused correct | unused wrong |",
             "|---|---|---|---|---|---|"]
    for name, row in result["methods"].items():
        cells = [_cell(row, group, key) for group, key in (("used", "correct"), ("used", "wrong"), ("used", "missed"),
                                                           ("unused", "correct"), ("unused", "wrong"))]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def format_f1_table(result: dict) -> str:
    """SLaTe-PRO's relocation F1 as markdown: per lookahead step and mean, averaged over households."""
    lines = [f"relocation F1 (SLaTe-PRO), households: {', '.join(result['households'])}", "",
             "| method | 10 min | 20 min | 30 min | 40 min | 50 min | 60 min | mean |", "|---" * 8 + "|"]
    for name, row in result["methods"].items():
        f1 = row["f1"]
        lines.append(f"| {name} | " + " | ".join(f"{v:.3f}" for v in f1["per_step"]) + f" | {f1['mean']:.3f} |")
    return "\n".join(lines)


def _cell(row: dict, group: str, key: str) -> str:
    mean, spread = row[group][key], row["spread"][group][key]
    return "n/a" if mean is None else f"{mean:.2f} (±{spread:.2f})"
