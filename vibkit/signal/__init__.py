"""Signal analysis for chain vibration, in the manner of :mod:`scipy.signal`.

Functions take an array, the sample rate ``fs`` [Hz] and keyword-only options (``axis=-1`` where
it applies); results with several fields are small frozen objects. This package imports numpy,
scipy, xarray and numba only, never the simulator.

Spectral analysis
    amplitude_spectrum, welch_psd, WelchResult, spectrogram, study_power_spectrum, compare_spectra,
    common_spectrograms, SpectrumComparison, HarmonicComparison
Filtering and outliers
    hampel, hampel_events, hampel_false_alarm_rate, hampel_n_sigma_for_rate, HampelResult,
    OutlierEvent
Peaks and frequency estimates
    link_pass_estimate, LinkPassEstimate, find_fundamental, Fundamental, Harmonic, harmonic_ls,
    interpolated_dft, FrequencyEstimate, crb_harmonic, crb_single_tone, mean_link_pass_frequency,
    MeanFrequency
Detection and invalid samples
    detect_link_pass, LinkPassDetection, flag_invalid, InvalidSamples, quantisation_step,
    steady_line, SteadyLine, line_level, walking_level, still_spans
Order tracking
    track_phase, PhaseTrack, phase_from_tacho, phase_from_shaft_angle, AngleSignal,
    resample_to_angle, order_spectrum, order_map, vold_kalman, VoldKalmanResult
Ride metrics (ISO 2631-1)
    frequency_weighting, frequency_weighting_response, frequency_weighting_sos, Weighting,
    WEIGHTINGS, lowpass_10hz, detect_ride_segment, RideSegment, half_cycle_peaks, peak_to_peak,
    peak_to_peak_values, PeakToPeak, a95
xarray wrappers
    amplitude_spectrum_da, welch_psd_da, spectrogram_da, hampel_da, link_pass_estimate_da,
    CombinedEstimate, sample_rate, split_segments

Everything else in the submodules is internal (kernels, helpers) and may change without notice;
:mod:`vibkit.signal.xr` holds the xarray wrappers, each the twin of a function above.
"""

from .compare import HarmonicComparison, SpectrumComparison, common_spectrograms, compare_spectra
from .detect import InvalidSamples, LinkPassDetection, detect_link_pass, flag_invalid
from .estimate import FrequencyEstimate, crb_harmonic, crb_single_tone, harmonic_ls, interpolated_dft
from .hampel import (
    HampelResult,
    OutlierEvent,
    hampel,
    hampel_events,
    hampel_false_alarm_rate,
    hampel_n_sigma_for_rate,
)
from .meanfreq import MeanFrequency, mean_link_pass_frequency
from .orders import (
    AngleSignal,
    PhaseTrack,
    VoldKalmanResult,
    order_map,
    order_spectrum,
    phase_from_shaft_angle,
    phase_from_tacho,
    resample_to_angle,
    track_phase,
    vold_kalman,
)
from .peaks import Fundamental, Harmonic, LinkPassEstimate, find_fundamental, link_pass_estimate
from .quantisation import quantisation_step
from .ride import (
    PeakToPeak,
    RideSegment,
    a95,
    detect_ride_segment,
    half_cycle_peaks,
    lowpass_10hz,
    peak_to_peak,
    peak_to_peak_values,
)
from .spectral import WelchResult, amplitude_spectrum, spectrogram, study_power_spectrum, welch_psd
from .steadyline import SteadyLine, line_level, steady_line
from .stillness import still_spans, walking_level
from .weighting import WEIGHTINGS, Weighting, frequency_weighting, frequency_weighting_response, frequency_weighting_sos
from .xr import (
    CombinedEstimate,
    amplitude_spectrum_da,
    hampel_da,
    link_pass_estimate_da,
    sample_rate,
    spectrogram_da,
    split_segments,
    welch_psd_da,
)

__all__ = [
    # Spectral analysis
    "amplitude_spectrum",
    "welch_psd",
    "WelchResult",
    "spectrogram",
    "study_power_spectrum",
    "compare_spectra",
    "common_spectrograms",
    "SpectrumComparison",
    "HarmonicComparison",
    # Filtering and outliers
    "hampel",
    "hampel_events",
    "hampel_false_alarm_rate",
    "hampel_n_sigma_for_rate",
    "HampelResult",
    "OutlierEvent",
    # Peaks and frequency estimates
    "link_pass_estimate",
    "LinkPassEstimate",
    "find_fundamental",
    "Fundamental",
    "Harmonic",
    "harmonic_ls",
    "interpolated_dft",
    "FrequencyEstimate",
    "crb_harmonic",
    "crb_single_tone",
    "mean_link_pass_frequency",
    "MeanFrequency",
    # Detection and invalid samples
    "detect_link_pass",
    "LinkPassDetection",
    "flag_invalid",
    "InvalidSamples",
    "quantisation_step",
    "steady_line",
    "SteadyLine",
    "line_level",
    "walking_level",
    "still_spans",
    # Order tracking
    "track_phase",
    "PhaseTrack",
    "phase_from_tacho",
    "phase_from_shaft_angle",
    "AngleSignal",
    "resample_to_angle",
    "order_spectrum",
    "order_map",
    "vold_kalman",
    "VoldKalmanResult",
    # Ride metrics (ISO 2631-1)
    "frequency_weighting",
    "frequency_weighting_response",
    "frequency_weighting_sos",
    "Weighting",
    "WEIGHTINGS",
    "lowpass_10hz",
    "detect_ride_segment",
    "RideSegment",
    "half_cycle_peaks",
    "peak_to_peak",
    "peak_to_peak_values",
    "PeakToPeak",
    "a95",
    # xarray wrappers
    "amplitude_spectrum_da",
    "welch_psd_da",
    "spectrogram_da",
    "hampel_da",
    "link_pass_estimate_da",
    "CombinedEstimate",
    "sample_rate",
    "split_segments",
]
