"""A run's settings from the parsed flags: the command line parses, :mod:`vibkit.diagnose.settings` resolves.

:func:`run_settings` hands a command's parsed options (--speed, --speed-uncertainty, --nominal-pitch, --teeth,
--links, --band, --limits, --segment) with the escalator profile and the recording to the one resolver,
:func:`vibkit.diagnose.settings.resolve_settings`, and says its notes; :func:`run_speed` and :func:`chain_links`
are its speed and its number of links alone.
"""

from __future__ import annotations

from .options import _profile_of, segment_of, speed_sigma
from .output import CLIError, msg

__all__ = ["chain_links", "profile_note", "run_settings", "run_speed"]


def run_speed(a, *, rec=None, scene=None, profile=None):
    """The run's one speed (:class:`vibkit.diagnose.speed.ResolvedSpeed`) as :func:`run_settings` resolves it:
    --speed, else the escalator profile's, else the recording's, else the scene's; --speed-uncertainty its sigma."""
    return run_settings(a, rec, _profile_of(a) if profile is None else profile, scene=scene, notes=False).speed


def run_settings(a, rec, profile, *, scene=None, frequency_only_band=False, notes=True):
    """The run's settings (:class:`vibkit.diagnose.settings.RunSettings`): the parsed flags handed to the one
    resolver (:func:`vibkit.diagnose.settings.resolve_settings`) with the profile and the recording; its notes (a
    link count filled in from the profile's geometry) said on stderr.  A --speed-uncertainty out of range or a
    --links the profile contradicts is a CLIError."""
    from vibkit.diagnose.settings import SettingsError, resolve_settings

    text = getattr(a, "speed_uncertainty", None)
    try:
        s = resolve_settings(
            rec,
            speed=getattr(a, "speed", None),
            speed_sigma=text,
            nominal_pitch=getattr(a, "nominal_pitch", None),
            teeth=getattr(a, "teeth", None),
            n_links=getattr(a, "links", None),
            band=getattr(a, "band", None),
            limits=getattr(a, "limits", None),
            segment=segment_of(a),
            profile=profile,
            scene=scene,
            frequency_only_band=frequency_only_band,
        )
    except SettingsError as exc:
        raise CLIError(str(exc)) from None
    if text is not None and s.speed.value is not None:
        speed_sigma(text, s.speed.value)  # the flag's own range checks (a bare number in m/s, at most 20 %)
    for n in s.notes if notes else ():
        msg(f"note: {n}")
    return s


def profile_note(settings, profile):
    """Say on stderr what the run took from the escalator profile (speed, nominal pitch, band, teeth)."""
    if profile is not None and settings.from_profile:
        # lines broken between the items only, never inside a value ("0.5 +- 0 m/s" stays one piece, whatever the
        # length of the profile's path before it)
        lines, line = [], f"note: from the profile {profile.source}:"
        for k, item in enumerate(settings.from_profile):
            piece = item + (";" if k < len(settings.from_profile) - 1 else "")
            if len(line) + 1 + len(piece) > 100 and line.strip():
                lines.append(line)
                line = " "
            line += " " + piece
        msg("\n".join([*lines, line]))


def chain_links(a, profile):
    """The chain's number of links as every command resolves it (:func:`vibkit.diagnose.settings.resolve_n_links`:
    --links, else the profile's ``chain.n_links``, else the number its scene fills in from its geometry, else None;
    the note on a filled-in count said on stderr); a --links that the profile's own ``chain.n_links`` contradicts is
    a CLIError (a wrong count scans a chain that is not there and flags nothing)."""
    from vibkit.diagnose.settings import SettingsError, resolve_n_links

    try:
        n, _, notes = resolve_n_links(getattr(a, "links", None), profile)
    except SettingsError as exc:
        raise CLIError(str(exc)) from None
    for note in notes:
        msg(f"note: {note}")
    return n
