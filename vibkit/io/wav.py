"""WAV files (RIFF ``WAVE``): integer PCM and IEEE float samples, read by scipy.io.wavfile.

One channel per WAV channel (``channel_1``, ``channel_2`` ...) at the rate of the ``fmt`` chunk.
A WAV file states no physical unit: integer samples stay in counts (full scale ``2**(bits-1)``,
said in the history), float samples (32- or 64-bit, full scale 1.0) stay as written; ``units=``
states the unit of one count or of 1.0 (``units="g/32768"``, ``units="g"``), converted to SI.
"""

from __future__ import annotations

import io
import warnings

import numpy as np

from ..runtime.reader_options import spell
from .errors import RecordingError
from .sampled import Column, assemble

__all__ = ["sniff_wav", "read_wav"]


def sniff_wav(probe) -> bool:
    return probe.head[:4] in (b"RIFF", b"RIFX", b"RF64") and probe.head[8:12] == b"WAVE"


def read_wav(path, data, options):
    """A WAV file (see the module docstring)."""
    from scipy.io import wavfile

    history = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            fs, samples = wavfile.read(io.BytesIO(data))
        except Exception as exc:  # scipy raises ValueError for a damaged or unsupported file
            raise RecordingError(
                path, None, f"cannot read as a WAV file (PCM or IEEE float): {type(exc).__name__}: {exc}"
            ) from None
    history += [f"scipy warning: {w.message}" for w in caught]
    samples = np.asarray(samples)
    if samples.ndim == 1:
        samples = samples[:, None]
    kind = samples.dtype
    if kind.kind in "iu":
        bits = 8 * kind.itemsize
        unit = "counts"
        history.append(
            f"WAV file: {samples.shape[1]} channel(s) of {bits}-bit integers at {fs} Hz; values in counts "
            f"(full scale {2 ** (bits - 1)}); pass {spell('units')} to scale them (e.g. 'g/{2 ** (bits - 1)}')"
        )
        if kind.kind == "u":  # 8-bit WAV is unsigned, centred on 128
            samples = samples.astype(np.float64) - 2 ** (bits - 1)
            history.append("8-bit unsigned samples centred on 128: 128 subtracted")
    else:
        unit = None
        history.append(
            f"WAV file: {samples.shape[1]} channel(s) of {8 * kind.itemsize}-bit floats at {fs} Hz "
            "(full scale 1.0); a WAV file states no unit"
        )
    columns = [
        Column(f"channel {c + 1}", samples[:, c].astype(np.float64), unit, {"wav_channel": c + 1}, f"channel_{c + 1}")
        for c in range(samples.shape[1])
    ]
    return assemble(
        path,
        data,
        reader="vibkit.io.wav",
        columns=columns,
        options=options,
        history=history,
        rate=float(fs),
        metadata=[("format", f"WAV {kind.name}")],
    )
