"""
A fleet's work list and trends
==============================

:class:`vibkit.fleet.FleetDB` keeps every measurement of every escalator of a fleet (SQLite here; a
PostgreSQL server for many technicians). ``fleet scan`` adds the recordings a catalogue lists,
``fleet status`` ranks the units by when their chain reaches a limit, and ``fleet report`` draws the work
list and each unit's elongation against date. The shipped example fleet: three escalators measured once
a year.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pypdfium2 as pdfium

import vibkit.datasets
from vibkit.diagnose.report import write_fleet_report
from vibkit.fleet import FleetDB

FLEET = vibkit.datasets.path("fleet-example")
work = Path(tempfile.mkdtemp())

with FleetDB(work / "fleet.sqlite") as db:
    db.scan(FLEET, FLEET / "units.csv", parallel=False)
    trends = db.status()
    measurements = db.measurements()
    links = {t.unit: db.links_history(t.unit) for t in trends}
for t in trends:
    print(
        f"{t.unit}: {t.latest_elongation_percent:.2f} +- {t.latest_elongation_sigma_percent:.2f} % "
        f"on {t.latest_date_utc[:10]}, {t.latest_verdict}"
    )

# %%
# The fleet PDF's first two pages: the work list, most urgent first, then elongation against date with
# 1-sigma bars, the fitted trend, the limits and when the next one is reached.

out = work / "fleet.pdf"
write_fleet_report(trends, measurements, out, database="fleet.sqlite", links=links)
pdf = pdfium.PdfDocument(out)  # PDFium renders the pages (the PDF itself is vector)
images = [np.asarray(pdf[k].render(scale=90 / 72).to_pil()) for k in range(2)]
landscape = images[0].shape[1] > images[0].shape[0]  # landscape pages one above the other, portrait side by side
rows, cols = (len(images), 1) if landscape else (1, len(images))
fig, axes = plt.subplots(rows, cols, figsize=(9, 6.2 * rows) if landscape else (11, 7.5), layout="constrained")
for ax, image in zip(axes, images):
    ax.imshow(image)
    ax.set_axis_off()
plt.show()
