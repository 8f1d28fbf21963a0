"""The paper's figures as PNG files (matplotlib, Agg backend): outcomes over windows, and over training days.

Inputs are plain dicts, as stored by benchmarks/paper_results.py:
- per window: outcome[method][window_min] = {"used": {"correct", "wrong", "missed"}, "unused": {"correct",
  "wrong"}} in objects per query (averaged over households), so a bar's height is the number of used (unused)
  objects per query and grows with the window, as in the paper's figure;
- per training-day count: summary[method][days] = {"used": {...}, "unused": {...}} percentages.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend is chosen first)

OUTCOME_COLOURS = {"correct": "#2e7d32", "wrong": "#c62828", "missed": "#9e9e9e"}


def window_bars(outcome: dict[str, dict[int, dict]], out: str | Path) -> Path:
    """Stacked bars per method and window: used objects (correct, wrong, missed) and unused (correct, wrong)."""
    methods = list(outcome)
    windows = sorted({w for per in outcome.values() for w in per})
    fig, axes = plt.subplots(1, 2, figsize=(max(8.0, 1.6 * len(methods) * 2), 4.5))
    width = 0.8 / max(len(windows), 1)
    for ax, group, keys in ((axes[0], "used", ("correct", "wrong", "missed")), (axes[1], "unused",
                                                                                   ("correct", "wrong"))):
        for m, method in enumerate(methods):
            for k, window in enumerate(windows):
                values = outcome[method].get(window)
                if values is None:
                    continue
                x, bottom = m + (k - (len(windows) - 1) / 2) * width, 0.0
                for key in keys:
                    height = values[group][key]
                    ax.bar(x, height, width * 0.95, bottom=bottom, color=OUTCOME_COLOURS[key],
                           label=key if (m, k) == (0, 0) else None)
                    bottom += height
        ax.set_xticks(range(len(methods)), methods, rotation=30, ha="right")
        ax.set_ylabel(f"{group} objects per query")
        if group == "unused":  # about 85 objects per query, a few wrong: the axis starts near the lowest bar
            totals = [sum(v[group].values()) for per in outcome.values() for v in per.values()]
            wrong = max((v[group]["wrong"] for per in outcome.values() for v in per.values()), default=0.0)
            ax.set_ylim(max(0.0, min(totals) - 4 * wrong - 1.0), max(totals) + 0.5)
            ax.set_ylabel(f"{group} objects per query (axis cut)")
        ax.set_title(f"{group} objects, windows {windows[0]}..{windows[-1]} min (left to right)")
        ax.legend(loc="upper left" if group == "used" else "lower left", fontsize=8)
    fig.tight_layout()
    return _save(fig, out)


def days_curve(summary: dict[str, dict[int, dict]], out: str | Path, title: str = "") -> Path:
    """Used correct %, used wrong % and unused wrong % against the number of training days, one line per method."""
    panels = (("used", "correct"), ("used", "wrong"), ("unused", "wrong"))
    fig, axes = plt.subplots(1, 3, figsize=(14, 4))
    for ax, (group, key) in zip(axes, panels, strict=True):
        for method, points in summary.items():
            days = sorted(d for d in points if points[d][group][key] is not None)
            ax.plot(days, [points[d][group][key] for d in days], marker="o", label=method)
        ax.set_xlabel("training days")
        ax.set_ylabel(f"% {group} objects {key}")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return _save(fig, out)


def _save(fig: plt.Figure, out: str | Path) -> Path:
    path = Path(out)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
