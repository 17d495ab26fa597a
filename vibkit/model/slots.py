"""Named slots of the arrays and tuples the compiled forward kernels pass around.

The compiled right-hand sides read their parameters from flat arrays (numba passes arrays and
tuples cheaply, not dicts or objects). Each array's layout is ONE ordered tuple of names below; the
module-level integer constants are looked up in it by name, so inserting a slot moves every
constant with it and nothing can shift silently. numba freezes module globals into the compiled
code as constants, so ``fp[FP_STIFFNESS]`` costs what ``fp[4]`` did. ``tests/test_architecture.py``
refuses a compiled kernel that indexes these arrays with a bare number, and
``tests/model/test_kernel_slots.py`` packs a scene with every effect and reads each slot back by name.

The arrays (see :func:`vibkit.model.effects.pack_parameters`, :class:`vibkit.model.effects.Work`
and :func:`vibkit.model.pitch_table.build_table`):

``prm``
    the parameter tuple: guide table, tooth corners, ``fp``, ``ip``, roller masses, and the
    passengers' masses, steps, boarding and alighting values, and the links' pitches.
``fp``
    float parameters (SI).
``ip``
    integer parameters: counts and one switch per effect (0 off; passengers 1 by time, 2 by place).
``ws``
    the work arrays of one evaluation (:class:`vibkit.model.effects.Work`); the last is ``info``.
``info``
    what an evaluation leaves for the outputs and for the next evaluation's closure.
``tb``, ``head``
    the pitch table and its header (:func:`vibkit.model.pitch_table.build_table`).
"""

from __future__ import annotations

from .schema import EFFECT_OPTIONS

__all__ = ["FP", "IP", "INFO", "PRM", "WS", "TB", "HEAD", "PART", "CTL", "COUNTERS"]


def _slots(names: tuple[str, ...]) -> dict[str, int]:
    if len(set(names)) != len(names):
        raise ValueError(f"duplicate slot names in {names}")
    return {name: i for i, name in enumerate(names)}


# --- the parameter tuple ------------------------------------------------------------------------
PRM_NAMES = (
    "table",
    "corners",
    "fp",
    "ip",
    "mass",
    "pass_mass",
    "pass_step",
    "pass_board",
    "pass_alight",
    "pitches",
    "radii",
    "teeth",
)
PRM = _slots(PRM_NAMES)
PRM_TABLE = PRM["table"]  # the guide's segment table (vibkit.model.guide)
PRM_CORNERS = PRM["corners"]  # tooth corners in the tooth's own frame (4, 2) [m]
PRM_FP = PRM["fp"]
PRM_IP = PRM["ip"]
PRM_MASS = PRM["mass"]  # roller masses (n) [kg]
PRM_PASS_MASS = PRM["pass_mass"]  # passengers' masses [kg]
PRM_PASS_STEP = PRM["pass_step"]  # passengers' steps (1-based)
PRM_PASS_BOARD = PRM["pass_board"]  # boarding time [s] or place (s0 of the step's middle roller) [m]
PRM_PASS_ALIGHT = PRM["pass_alight"]  # alighting time [s] or place [m]
PRM_PITCHES = PRM["pitches"]  # link lengths (n) [m]
PRM_RADII = PRM["radii"]  # roller radii (n) [m]
PRM_TEETH = PRM["teeth"]  # the sprocket's tooth table (vibkit.model.sprocket.tooth_table)

# --- float parameters ---------------------------------------------------------------------------
FP_NAMES = (
    "p0",
    "lt",
    "pitch",
    "g",
    "k",
    "expo",
    "damp",
    "kp",
    "ki",
    "wref",
    "tlim",
    "k_s",
    "preload",
    "m_c",
    "mu_rr",
    "inertia",
    "r_d",
    "cx",
    "cz",
    "root_r",
    "psi",
    "tol",
    "reach",
)
FP = _slots(FP_NAMES)
FP_P0 = FP["p0"]  # length of the undeformed guide (one loop) [m]
FP_LT = FP["lt"]  # undeformed length of a telescopic run [m]
FP_PITCH = FP["pitch"]  # link pitch [m]
FP_G = FP["g"]  # gravity [m/s^2]
FP_STIFFNESS = FP["k"]  # contact stiffness [N/m^exponent]
FP_EXPONENT = FP["expo"]  # contact exponent
FP_DAMPING = FP["damp"]  # contact damping [s/m]
FP_KP = FP["kp"]  # motor's proportional gain [N m s]
FP_KI = FP["ki"]  # motor's integral gain [N m]
FP_SPEED_REF = FP["wref"]  # sprocket's reference speed [rad/s]
FP_TORQUE_LIMIT = FP["tlim"]  # motor's torque limit [N m]
FP_TENSIONER_STIFFNESS = FP["k_s"]  # carriage spring [N/m]
FP_PRELOAD = FP["preload"]  # carriage spring's preload [N]
FP_CARRIAGE_MASS = FP["m_c"]  # [kg]
FP_ROLLING = FP["mu_rr"]  # rolling-resistance coefficient
FP_INERTIA = FP["inertia"]  # sprocket's moment of inertia [kg m^2]
FP_ROLLER_RADIUS = FP["r_d"]  # [m]
FP_CX = FP["cx"]  # sprocket centre x [m]
FP_CZ = FP["cz"]  # sprocket centre z [m]
FP_ROOT_RADIUS = FP["root_r"]  # sprocket's root radius [m]
FP_TOOTH_PITCH = FP["psi"]  # angle between teeth [rad]
FP_CLOSURE_TOL = FP["tol"]  # closure tolerance [m]
FP_REACH = FP["reach"]  # farthest a roller centre touching a tooth sits from the sprocket centre [m]

# --- integer parameters -------------------------------------------------------------------------
# one switch per effect of the scene's schema, named as the effect (vibkit.model.schema.EFFECT_OPTIONS):
# a new effect gets its switch here by being declared there
IP_NAMES = ("n", "nteeth", *EFFECT_OPTIONS, "links_per_step")
IP = _slots(IP_NAMES)
IP_N = IP["n"]  # number of rollers
IP_TEETH = IP["nteeth"]  # number of teeth
IP_GRAVITY = IP["gravity"]
IP_CONTACT = IP["contact"]
IP_MOTOR = IP["motor"]
IP_PASSENGERS = IP["passengers"]  # 0 none, 1 by time, 2 by place
IP_TENSIONER = IP["tensioner"]
IP_ROLLING = IP["rolling_resistance"]
IP_LINKS_PER_STEP = IP["links_per_step"]  # rollers per step (3, or 4 on 101.6 mm chains)

PASSENGERS_BY_TIME = 1
PASSENGERS_BY_PLACE = 2

# --- work arrays --------------------------------------------------------------------------------
WS_NAMES = (
    "s0",
    "segment",
    "lam",
    "x",
    "z",
    "part",
    "alpha",
    "beta",
    "jac",
    "gam",
    "hacc",
    "eta",
    "sd",
    "fx",
    "fz",
    "cand",
    "indentation",
    "tooth_force",
    "info",
)
WS = _slots(WS_NAMES)
WS_INFO = WS["info"]
WS_S0, WS_X, WS_Z, WS_JAC, WS_HACC = WS["s0"], WS["x"], WS["z"], WS["jac"], WS["hacc"]

# --- a roller's place and partials (ws[WS["part"]] rows, vibkit.model.guide.point_partials) ------
# r = (x, z) and its partials in s0 (the roller's coordinate, "s") and delta ("d")
PART_NAMES = ("x", "z", "x_s", "z_s", "x_d", "z_d", "x_ss", "z_ss", "x_sd", "z_sd", "x_dd", "z_dd")
PART = _slots(PART_NAMES)
PART_X, PART_Z = PART["x"], PART["z"]  # [m]
PART_XS, PART_ZS = PART["x_s"], PART["z_s"]  # dr/ds0
PART_XD, PART_ZD = PART["x_d"], PART["z_d"]  # dr/ddelta
PART_XSS, PART_ZSS = PART["x_ss"], PART["z_ss"]  # d2r/ds0^2 [1/m]
PART_XSD, PART_ZSD = PART["x_sd"], PART["z_sd"]  # d2r/ds0 ddelta [1/m]
PART_XDD, PART_ZDD = PART["x_dd"], PART["z_dd"]  # d2r/ddelta^2 [1/m]

# --- what an evaluation leaves (ws[WS_INFO]) ----------------------------------------------------
INFO_NAMES = (
    "delta",
    "delta_dot",
    "delta_ddot",
    "motor",
    "torque_c",
    "energy_c",
    "worst",
    "active",
    "f_drive",
    "f_back",
    "at",
    "slope",
    "dh_ddelta",
    "walks",
    "curvature",
)
INFO = _slots(INFO_NAMES)
INFO_DELTA = INFO["delta"]  # tensioner displacement [m]
INFO_DELTA_DOT = INFO["delta_dot"]  # [m/s]
INFO_DELTA_DDOT = INFO["delta_ddot"]  # [m/s^2]
INFO_MOTOR = INFO["motor"]  # motor torque [N m]
INFO_TORQUE_C = INFO["torque_c"]  # contact torque on the sprocket [N m]
INFO_ENERGY_C = INFO["energy_c"]  # contact energy [J]
INFO_WORST = INFO["worst"]  # largest indentation [m]
INFO_ACTIVE = INFO["active"]  # active contacts
INFO_F_DRIVE = INFO["f_drive"]  # driving-flank force [N]
INFO_F_BACK = INFO["f_back"]  # back-flank force [N]
INFO_AT = INFO["at"]  # s0_1 of the last evaluation [m]
INFO_SLOPE = INFO["slope"]  # d delta / d s0_1 there
INFO_DH_DDELTA = INFO["dh_ddelta"]  # dh/ddelta of the closure there
INFO_WALKS = INFO["walks"]  # closure walks so far
INFO_CURVATURE = INFO["curvature"]  # d2 delta / d s0_1^2 there [1/m]
# the closure's memory (at, slope, dh/ddelta: consecutive slots), zeroed to close from delta alone
INFO_MEMORY = INFO_AT
INFO_MEMORY_END = INFO_DH_DDELTA + 1
if (INFO_SLOPE, INFO_DH_DDELTA) != (INFO_AT + 1, INFO_AT + 2):
    raise ValueError("the closure's memory slots must be consecutive")

# --- the forward integrator's step control and counters (vibkit.analyses.integrate) ---------------
CTL_NAMES = ("last_error", "rejected", "wanted_step", "has_breakpoint", "breakpoint", "direction")
CTL = _slots(CTL_NAMES)
CTL_LAST_ERROR = CTL["last_error"]  # the last accepted step's error norm (the controller's memory)
CTL_REJECTED = CTL["rejected"]  # 1.0 right after a rejected step (no growth then)
CTL_WANTED_STEP = CTL["wanted_step"]  # the step the error controller wanted before a breakpoint cut it [s]
CTL_HAS_BREAKPOINT = CTL["has_breakpoint"]  # 1.0: the step starts on a breakpoint (remembered below)
CTL_BREAKPOINT = CTL["breakpoint"]  # that breakpoint, along roller 1's coordinate [m]
CTL_DIRECTION = CTL["direction"]  # the direction of motion when it was remembered (+1 or -1)

COUNTER_NAMES = ("steps", "rejected", "evaluations", "event_steps", "event_retries", "landings")
COUNTERS = _slots(COUNTER_NAMES)
COUNT_STEPS = COUNTERS["steps"]  # accepted steps
COUNT_REJECTED = COUNTERS["rejected"]  # rejected steps
COUNT_EVALUATIONS = COUNTERS["evaluations"]  # right-hand-side evaluations
COUNT_EVENT_STEPS = COUNTERS["event_steps"]  # steps that ended on a breakpoint
COUNT_EVENT_RETRIES = COUNTERS["event_retries"]  # steps retried to land on one
COUNT_LANDINGS = COUNTERS["landings"]  # landings on a breakpoint

# --- the pitch table ----------------------------------------------------------------------------
TB_NAMES = (
    "head",
    "sb",
    "uc",
    "up",
    "mc",
    "vc",
    "dc",
    "xc",
    "zc",
    "sc",
    "cand",
    "cc",
    "rstep",
    "rnext",
    "runs",
    "raux",
)
TB = _slots(TB_NAMES)
TB_HEAD = TB["head"]  # see HEAD_NAMES
TB_SB = TB["sb"]  # piece ends along roller 1's coordinate, the whole loop [m]
TB_UC = TB["uc"]  # u(s) quintics per piece of the loop
TB_UP = TB["up"]  # node values of u over one pitch [m]
TB_MC = TB["mc"]  # generalised mass quintics
TB_VC = TB["vc"]  # gravity's potential quintics
TB_DC = TB["dc"]  # delta quintics
TB_XC = TB["xc"]  # x of each table roller (n, pieces, 6)
TB_ZC = TB["zc"]  # z of each table roller
TB_SC = TB["sc"]  # s0 of each table roller
TB_CAND = TB["cand"]  # table rollers that can reach a tooth
TB_CC = TB["cc"]  # the candidates' x and z quintics side by side (pieces, candidates, 12)
# the closure walked run by run (vibkit.model.runs), for chains the table cannot stand for; empty otherwise
TB_RSTEP = TB[
    "rstep"
]  # per segment: one link's arc length, its turn's cosine and sine, near the sprocket, sine of half the turn (nseg, 5)
TB_RNEXT = TB["rnext"]  # (n + 1,) int64: the first link at or after each roller of another pitch
TB_RUNS = TB["runs"]  # scratch: one row per run of the last walk
TB_RAUX = TB["raux"]  # scratch: the walk's partials at roller 1 and the ghost, runs walked

HEAD_NAMES = ("a", "p0", "pieces", "n", "link_error", "by_roller", "runs")
HEAD = _slots(HEAD_NAMES)
HEAD_A = HEAD["a"]  # the first breakpoint, where the pitch starts [m]
HEAD_P0 = HEAD["p0"]  # loop length [m]
HEAD_PIECES = HEAD["pieces"]  # pieces over one pitch
HEAD_N = HEAD["n"]  # rollers
HEAD_LINK_ERROR = HEAD["link_error"]  # the tabulated chain's largest link-length error [m]
HEAD_BY_ROLLER = HEAD["by_roller"]  # 1.0: the rollers' masses or radii differ (sums taken roller by roller)
HEAD_RUNS = HEAD["runs"]  # 1.0: no table; the chain is closed run by run (vibkit.model.runs)
