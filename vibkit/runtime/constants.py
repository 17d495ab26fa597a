"""Physical constants that more than one layer uses (the lowest layer, so that ``io`` and ``signal`` may too).

Two different accelerations of gravity appear in vibkit, on purpose:

* :data:`STANDARD_GRAVITY` = 9.80665 m/s^2, the conventional value that defines the unit "g" (3rd CGPM,
  1901): an accelerometer reading in g is converted to m/s^2 with it.
* the model's gravity, 9.81 m/s^2 (the study and ``model.md``), the default of the scene key
  ``effects.gravity.g`` (:data:`vibkit.model.params.GRAVITY`): what pulls the simulated chain down.
"""

__all__ = ["STANDARD_GRAVITY", "A4_PORTRAIT_IN", "A4_LANDSCAPE_IN"]

#: Standard acceleration of gravity (3rd CGPM, 1901), the definition of the unit g. [m/s^2]
STANDARD_GRAVITY = 9.80665

#: an A4 page, portrait, in inches (matplotlib's figure size): the reports' pages and the figures drawn like them
A4_PORTRAIT_IN = (8.27, 11.69)
#: an A4 page lying on its side, width and height [in]
A4_LANDSCAPE_IN = (11.69, 8.27)
