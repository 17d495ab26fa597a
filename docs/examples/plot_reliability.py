"""
What bad inputs give
====================

``python benchmarks/reliability.py`` runs a corpus of bad inputs (scenes, options, outputs, recordings,
full disks, fleet databases...) through the command line, each in a fresh process, and records what
came back: a clean one-line error, a result, a clean interruption, or a failure (a traceback, a crash,
a hang, a lost file, an unexpected exit code). This draws the table it last wrote,
``benchmarks/results/reliability.csv``, by family of input.
"""

from pathlib import Path

import matplotlib.pyplot as plt
import pandas as pd

CSV = Path.cwd().resolve().parents[1] / "benchmarks" / "results" / "reliability.csv"
runs = pd.read_csv(CSV)
table = runs.pivot_table(index="item", columns="outcome", values="case", aggfunc="count", fill_value=0)
print(f"{len(runs)} cases; outcomes: {runs['outcome'].value_counts().to_dict()}")
print(f"passed (the outcome expected): {int(runs['passed'].sum())} of {len(runs)}")

ax = table.loc[table.sum(axis=1).sort_values().index].plot.barh(
    stacked=True, figsize=(8, 6), width=0.8, colormap="tab10"
)
ax.set_xlabel("cases")
ax.set_ylabel("family of bad input")
ax.legend(title="outcome", loc="lower right")
plt.tight_layout()
plt.show()
