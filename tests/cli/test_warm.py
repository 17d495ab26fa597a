"""`vibkit warm` compiles ahead what the commands run: after it, the model's right-hand sides, its integrator, the
inverse analysis and the signal layer's compiled filters are in numba's cache (as numba itself would find them:
:func:`vibkit.runtime.kernel_cache.kernel_cached`), and it says so in --json and on stderr."""

import json

from vibkit.analyses import integrate, inverse
from vibkit.analyses.warm_up import STEPS
from vibkit.model import pitch_table, runs_rhs
from vibkit.runtime.kernel_cache import kernel_cached
from vibkit.signal import kernels

#: (module file, kernel): what the commands run, each step of `vibkit warm` compiles some of them
KERNELS = [
    (pitch_table.__file__, "rhs"),
    (runs_rhs.__file__, "runs_observe"),
    (integrate.__file__, "_dopri5_chunk"),
    (inverse.__file__, "inverse_positions"),
    (kernels.__file__, "_hampel_core"),
    (kernels.__file__, "_vk_solve"),
    (kernels.__file__, "_half_cycle_peak_index"),
]


def test_warm_leaves_every_kernel_the_commands_run_in_the_cache(run):
    rc, out, err = run("warm", "--json")
    assert rc == 0, err
    d = json.loads(out)
    assert d["schema"] == "vibkit.warm/1"
    assert [s["what"] for s in d["steps"]] == [what for what, _ in STEPS]
    assert all(s["cpu_s"] >= 0 for s in d["steps"]) and d["cpu_s"] >= sum(s["cpu_s"] for s in d["steps"]) * 0.999
    missing = [name for path, name in KERNELS if not kernel_cached(path, name)]
    assert not missing, missing
    # run again, everything is loaded, not compiled, and the table says it
    rc, out, err = run("warm")
    assert rc == 0, err
    assert "already compiled: loaded from the cache" in err
    assert all(what in out for what, _ in STEPS)
