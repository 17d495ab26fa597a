"""Signal analysis for chain vibration: spectra, Hampel filter, harmonic families, frequency
estimation with Cramer-Rao sigmas, order tracking, Vold-Kalman filtering, spectrum comparison.

Functions follow scipy.signal conventions (array, ``fs`` [Hz], keyword-only options, ``axis=-1``);
:mod:`vibkit.signal.xr` wraps them for xarray objects and keeps units.  This package imports
numpy, scipy, xarray and numba only -- never the simulator.
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
    "WEIGHTINGS",
    "PeakToPeak",
    "RideSegment",
    "Weighting",
    "a95",
    "detect_ride_segment",
    "frequency_weighting",
    "frequency_weighting_response",
    "frequency_weighting_sos",
    "half_cycle_peaks",
    "lowpass_10hz",
    "peak_to_peak",
    "peak_to_peak_values",
    "InvalidSamples",
    "LinkPassDetection",
    "MeanFrequency",
    "detect_link_pass",
    "flag_invalid",
    "mean_link_pass_frequency",
    "quantisation_step",
    "AngleSignal",
    "CombinedEstimate",
    "FrequencyEstimate",
    "Fundamental",
    "HampelResult",
    "Harmonic",
    "HarmonicComparison",
    "LinkPassEstimate",
    "OutlierEvent",
    "PhaseTrack",
    "SpectrumComparison",
    "VoldKalmanResult",
    "WelchResult",
    "amplitude_spectrum",
    "amplitude_spectrum_da",
    "common_spectrograms",
    "compare_spectra",
    "crb_harmonic",
    "crb_single_tone",
    "find_fundamental",
    "hampel",
    "hampel_da",
    "hampel_events",
    "hampel_false_alarm_rate",
    "hampel_n_sigma_for_rate",
    "harmonic_ls",
    "interpolated_dft",
    "link_pass_estimate",
    "link_pass_estimate_da",
    "order_map",
    "order_spectrum",
    "phase_from_shaft_angle",
    "phase_from_tacho",
    "resample_to_angle",
    "sample_rate",
    "spectrogram",
    "spectrogram_da",
    "split_segments",
    "study_power_spectrum",
    "track_phase",
    "vold_kalman",
    "welch_psd",
    "welch_psd_da",
]
