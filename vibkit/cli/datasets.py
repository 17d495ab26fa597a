"""``vibkit datasets``: the example recordings and the example fleet that ship with vibkit (:mod:`vibkit.datasets`)."""

from __future__ import annotations

from .options import add_command, add_json
from .output import CLIError, msg, print_json, table

EPILOG = (
    "examples:\n"
    "  vibkit datasets copy data     # data/field/..., data/fleet-example/...: the documentation's\n"
    "                                # examples then run as written from this folder\n"
    '  vibkit pitch "$(vibkit datasets path leon-tensioner)" --speed 0.49\n'
    "  vibkit datasets list --json   # every file, its size and its provenance\n"
    "none of these files is an original field recording: vibkit's scripts made them (reconstructions\n"
    "of the study's two field cases, logger layouts, a synthetic fleet); 'vibkit datasets list' says\n"
    "where their provenance is written in full"
)


def add_parser(subparsers):
    s = add_command(
        subparsers, "datasets", "the example recordings and example fleet shipped with vibkit: list, path, copy", EPILOG
    )
    dsub = s.add_subparsers(dest="datasets_command", metavar="SUBCOMMAND", required=True)

    d = add_command(dsub, "list", "every shipped example file, its size and its provenance", EPILOG)
    add_json(d)
    d.set_defaults(func=run_list)

    d = add_command(dsub, "path", "print the path of a shipped example file or folder", EPILOG)
    d.add_argument(
        "name",
        help="a path under data/ (field/leon-tensioner.csv), a file's name without extension where unique "
        "(leon-tensioner, phyphox, units) or a folder (fleet-example)",
    )
    d.set_defaults(func=run_path)

    d = add_command(
        dsub,
        "copy",
        "copy every example file into a folder, in the repository's layout (DIR/field, DIR/fleet-example)",
        EPILOG,
    )
    d.add_argument("directory", metavar="DIR", help="folder to copy into (made if missing), e.g. data")
    d.add_argument(
        "--force", action="store_true", help="replace example files of the same name that have other contents"
    )
    add_json(d)
    d.set_defaults(func=run_copy)
    return s


def run_list(a):
    import vibkit.datasets as ds

    root = ds.folder()
    rows = [(name, (root / name).stat().st_size, ds.provenance(name)) for name in ds.names()]
    if getattr(a, "json", False):
        print_json(
            "datasets",
            {
                "folder": str(root),
                "licence": ds.LICENCE,
                "files": [{"name": n, "bytes": b, "provenance": p} for n, b, p in rows],
            },
        )
        return 0
    print(table([(n, b) for n, b, _ in rows], header=("file (under data/)", "bytes")))
    for top, text in ds.FOLDERS.items():
        msg(f"{top}/: {text}")
    msg(f"licence: {ds.LICENCE}; provenance in full: {root / 'README.md'}")
    return 0


def run_path(a):
    import vibkit.datasets as ds

    try:
        print(ds.path(a.name))
    except ValueError as exc:
        raise CLIError(str(exc)) from None
    return 0


def run_copy(a):
    import vibkit.datasets as ds

    try:
        written = ds.copy(a.directory, force=a.force)
    except FileExistsError as exc:
        raise CLIError(str(exc)) from None
    total = len(ds.names())
    if a.json:
        print_json("datasets", {"folder": a.directory, "written": [str(p) for p in written], "files": total})
    same = total - len(written)
    msg(
        f"vibkit datasets copy: wrote {len(written)} of {total} example files into {a.directory}"
        + (f" ({same} already there, same bytes)" if same else "")
    )
    return 0
