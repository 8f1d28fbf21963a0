"""The paper's table as text: percentages of used and unused object-queries per method."""

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


def _cell(row: dict, group: str, key: str) -> str:
    mean, spread = row[group][key], row["spread"][group][key]
    return "n/a" if mean is None else f"{mean:.2f} (±{spread:.2f})"
