"""
A report's first pages
======================

:func:`vibkit.diagnose.report.write_report` (``vibkit report``) writes one PDF per recording: page 1 the
verdict with its evidence, then the recording, its time signal, spectrum, spectrogram, order spectrum and
the rest (the pages are listed on :doc:`/guide/reports`). Here the tensioner recording of the Leon
escalator with its measured chain speed and nominal pitch, without a scene (so nothing is simulated), and
its first two pages drawn as pictures.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pypdfium2 as pdfium

import vibkit.datasets
from vibkit.diagnose.report import write_report

out = Path(tempfile.mkdtemp()) / "leon.pdf"
report = write_report(
    vibkit.datasets.path("field/leon-tensioner.csv"), out, speed=0.49, speed_sigma=0.49e-3, nominal_pitch=0.13333
)
print(out.name, "pages:", ", ".join(title for title, _ in report.pages))

# %%
# The first two pages as images.

pdf = pdfium.PdfDocument(out)  # PDFium renders the pages (the PDF itself is vector)
images = [np.asarray(pdf[k].render(scale=90 / 72).to_pil()) for k in range(2)]
landscape = images[0].shape[1] > images[0].shape[0]  # landscape pages one above the other, portrait side by side
rows, cols = (len(images), 1) if landscape else (1, len(images))
fig, axes = plt.subplots(rows, cols, figsize=(9, 6.2 * rows) if landscape else (11, 7.5), layout="constrained")
for ax, image in zip(axes, images):
    ax.imshow(image)
    ax.set_axis_off()
plt.show()
