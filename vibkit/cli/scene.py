"""``vibkit scene``: the scene (TOML) of an escalator described by a profile."""

from __future__ import annotations

import sys

from .options import add_command, add_force_overwrite, positive
from .output import CLIError, check_output, msg

EPILOG = (
    "example:\n  vibkit scene data/fleet-example/escalators/E07.toml --analysis forward -o E07-forward.toml\n"
    "  vibkit simulate E07-forward.toml -o E07.nc --check\n"
    "what the profile does not say is filled from standard step-chain proportions; the scene's\n"
    "comments say what was filled and from what. A geometry that cannot run is refused, naming the key."
)


def add_parser(subparsers):
    s = add_command(subparsers, "scene", "write the scene (TOML) of an escalator profile", EPILOG)
    s.add_argument(
        "profile",
        help="the escalator's profile (TOML); see the guide 'Your escalator' (an example: vibkit datasets path E07.toml)",
    )
    s.add_argument(
        "--analysis", choices=("forward", "inverse"), default="forward", help="the scene's analysis (default forward)"
    )
    s.add_argument("--duration", type=positive, help="the run's length [s] (default 20 forward, 10 inverse)")
    s.add_argument("-o", "--output", required=True, help="scene file to write (.toml); - for stdout")
    add_force_overwrite(s, "scene file")
    s.set_defaults(func=run)
    return s


def run(a):
    from vibkit.model.profile import load_profile
    from vibkit.model.scene import SceneError

    check_output(a.output, [a.profile], a.force)
    try:
        profile = load_profile(a.profile)
        profile.scene(a.analysis, a.duration)  # refuses a geometry that cannot run, naming the key
        text = profile.scene_text(a.analysis, a.duration)
    except SceneError as exc:
        raise CLIError(str(exc)) from None
    from vibkit.model.profile_scene import geometry_note

    if note := geometry_note(profile):  # chain.n_links alone: built as a 30 deg escalator, said
        msg(f"note: {note}")
    if a.output == "-":
        sys.stdout.write(text)
        return 0
    from vibkit.runtime.safe_output import atomic_output

    with atomic_output(a.output, overwrite=a.force, inputs=[a.profile]) as tmp:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)
    msg(f"vibkit scene: wrote {a.output} ({a.analysis} scene of {profile.name}); run it with vibkit simulate")
    return 0
