"""One trial of a study: a virtual robot drawn from its factors and seed, put through the whole
method (sample, measure, calibrate, validate, evaluate the paths), reduced to one row. A planar
robot runs pcr.run_method, a spatial one (a robot file with "kind": "spatial")
pcr.run_spatial_method; the factors that mean nothing for the robot's kind are refused.

Needs only numpy and pcr, so that a worker process imports nothing else to run trials.
"""
from __future__ import annotations

import json
import math
import numbers
import time
from dataclasses import dataclass

import numpy as np

import pcr


@dataclass(frozen=True)
class Factor:
    """A factor of a trial: its type, its value when a study does not set it, its unit, and for
    a string its choices (empty: any)."""

    kind: type
    default: object
    unit: str
    doc: str
    choices: tuple = ()


# None as a default: the robot description's own value (tolerances) or pcr's default.
FACTORS = {
    "robot": Factor(str, "default", "",
                    "the design: 'default' (the paper's robot), 'continuum-stewart-gough' (the "
                    "spatial reference robot) or a robot JSON file, planar or spatial"),
    "mount_tolerance": Factor(float, None, "m",
                              "half-width of the mount positions A and B (machining), each "
                              "coordinate; the truth is drawn inside it"),
    "angle_tolerance": Factor(float, None, "rad", "half-width of alpha, beta, gamma"),
    "length_tolerance": Factor(float, None, "m", "half-width of the rod lengths l"),
    "diameter_tolerance": Factor(float, None, "m", "half-width of the wire diameter d (one wire)"),
    "mount_measurement": Factor(float, 0.0, "m",
                                "half-width of the mounts' measurement: the nominal model is the "
                                "truth's A and B plus U(-h, h); 0: the nominal is the design"),
    "noise_position": Factor(float, None, "m", "standard deviation of the camera's position"),
    "noise_angle": Factor(float, None, "rad", "standard deviation of the camera's angle"),
    "calibration_count": Factor(int, None, "", "calibration configurations"),
    "validation_count": Factor(int, 56, "", "validation configurations"),
    "design": Factor(str, "poisson-disc", "", "choice of the configurations: 'poisson-disc' or "
                     "'d-optimal'", ("poisson-disc", "d-optimal")),
    "model": Factor(str, "stages", "", "the calibrated model: 'stages' (the paper's), 'load' (the "
                    "last stage also frees a constant platform load: f_x, f_y, m_z planar, the six of "
                    "a force and a moment spatial) or 'selected' (the load "
                    "model when the residuals exceed the noise and the validation set supports "
                    "it, pcr.calibrate_selecting_model)", ("stages", "load", "selected")),
    "attachment_scale": Factor(float, None, "",
                               "spatial: the description's half-widths of the rods' attachments "
                               "(A, B and the base and tip turns) times this; the truth is drawn "
                               "inside them"),
    "misalignment": Factor(float, 0.0, "rad",
                           "unmodelled: U(-h, h) added to beta and gamma (planar), to each base "
                           "turn component (spatial)"),
    "diameter_spread": Factor(float, 0.0, "m", "unmodelled: U(-h, h) added to each rod's d, on "
                              "its own (planar and spatial)"),
    "load_force_x": Factor(float, 0.0, "N", "unmodelled: a constant force on the platform"),
    "load_force_y": Factor(float, 0.0, "N", "unmodelled: a constant force on the platform"),
    "load_moment": Factor(float, 0.0, "N m", "unmodelled: a constant moment on the platform"),
    "payload": Factor(float, 0.0, "kg", "spatial, unmodelled: a mass at the platform's origin"),
    "rod_density": Factor(float, None, "kg/m^3",
                          "spatial, unmodelled: the true rods' density (the model's: as "
                          "described)"),
    "repeat": Factor(int, 30, "", "ISO 9283 cycles per pose of the square and the circle"),
}

_TABLE3_SETS = ("nominal_model_calibration_set", "nominal_model_validation_set",
                "identified_model_calibration_set", "identified_model_validation_set")
_ISO_STATS = ("ap_p", "ap_theta_abs", "rp_l", "rp_theta")
_PATHS = ("square", "circle")
_MODELS = ("nominal", "identified")
_TIMES = ("sampling", "measurement", "calibration", "validation", "accuracy")
_SPATIAL_PATHS = ("square", "circle", "helix")
_SPATIAL_ISO_STATS = ("ap_p", "rp_l")

# The factors of one kind of robot only: set to another value than their default, they are
# refused for the other kind.
PLANAR_ONLY = ("mount_tolerance", "angle_tolerance", "length_tolerance", "diameter_tolerance",
               "mount_measurement", "load_force_x", "load_force_y", "load_moment")
SPATIAL_ONLY = ("attachment_scale", "payload", "rod_density")


def check_factor(name, value, where):
    """The value of factor `name` converted to its type; ValueError naming `where`, the factor and
    the value when it is unknown or of the wrong type or sign."""
    if name not in FACTORS:
        raise ValueError(f"{where}: unknown factor {name!r} (known: {', '.join(FACTORS)})")
    factor = FACTORS[name]
    if value is None:
        return None
    if factor.kind is str:
        if not isinstance(value, str):
            raise ValueError(f"{where}: {name} = {value!r}: expected a string")
        if factor.choices and value not in factor.choices:
            raise ValueError(f"{where}: {name} = {value!r}: expected one of "
                             f"{', '.join(map(repr, factor.choices))}")
        return value
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{where}: {name} = {value!r}: expected a number ({factor.unit or 'count'})")
    if factor.kind is int and value != int(value):
        raise ValueError(f"{where}: {name} = {value!r}: expected a whole number")
    value = factor.kind(value)
    if not math.isfinite(value) or (value < 0 and not name.startswith("load_")):
        raise ValueError(f"{where}: {name} = {value!r}: expected a finite value >= 0")
    if name in ("calibration_count", "validation_count", "repeat") and value < 1:
        raise ValueError(f"{where}: {name} = {value!r}: expected at least 1")
    return value


def factor_values(factors):
    """Every factor's value: those of `factors`, the defaults for the others."""
    return {name: factors.get(name, f.default) for name, f in FACTORS.items()}


def check_applicable(factors, robot, where="run_trial"):
    """ValueError naming the factor when `factors` (those a study sets) set one that does not
    apply to `robot`'s kind (a pcr.Robot or a pcr.SpatialRobot)."""
    spatial = isinstance(robot, pcr.SpatialRobot)
    foreign, kind = (PLANAR_ONLY, "spatial") if spatial else (SPATIAL_ONLY, "planar")
    for name in foreign:
        if name in factors and factors[name] != FACTORS[name].default:
            own = [n for n in FACTORS if n not in foreign]
            raise ValueError(
                f"{where}: factor {name} = {factors[name]!r} does not apply to the {kind} robot "
                f"{robot.name!r} (a {kind} trial's factors: {', '.join(own)})")


def spatial_outcome_columns():
    """The outcome columns of a spatial trial's row, named as in pcr's spatial JSON reports (SI
    units), in order: Table 3 (e_p_m, e_angle_rad and the rms errors), the noise and its floor
    sqrt(3) sigma, Table 4 in 3-D on the square, the circle and the helix, the calibration."""
    columns = []
    for s in _TABLE3_SETS:
        for quantity in ("e_p_m", "e_angle_rad"):
            columns += [f"table3.{s}.{quantity}.{stat}" for stat in ("max", "mean")]
        columns += [f"table3.{s}.{q}" for q in ("rms_position_m", "rms_angle_rad", "failed",
                                                "branch_mismatches")]
    columns += ["noise.position_m", "noise.angle_rad", "noise.floor_position_m",
                "noise.floor_angle_rad"]
    for path in _SPATIAL_PATHS:
        for model in _MODELS:
            for stat in _SPATIAL_ISO_STATS:
                columns += [f"accuracy.{path}.{model}.{stat}.{s}" for s in ("max", "mean")]
            columns += [f"accuracy.{path}.{model}.ap_abc_abs.{a}.max" for a in "abc"]
    columns += ["configurations.calibration", "configurations.validation",
                "configurations.unreachable", "calibration.iterations",
                "calibration.load_identified", "calibration.residual_variance",
                "calibration.free_parameters", "calibration.jacobian_rank", "calibration.at_bound"]
    columns += [f"time.{t}_s" for t in _TIMES] + ["time_s"]
    return columns


def robot_columns(robot):
    """The outcome columns of a trial on `robot` (a pcr.Robot or a pcr.SpatialRobot)."""
    if isinstance(robot, pcr.SpatialRobot):
        return spatial_outcome_columns()
    return outcome_columns(pcr.parameter_names(robot.num_limbs))


def study_columns(robots):
    """The outcome columns of a study on `robots` (robot JSON texts by name): every kind's, the
    largest planar robot's parameters (smaller ones leave the rest NaN), in order."""
    columns = {}
    kinds = [pcr.Robot.from_json(t) for t in robots.values()]
    planar = [r for r in kinds if not isinstance(r, pcr.SpatialRobot)]
    if planar:
        columns.update(dict.fromkeys(robot_columns(max(planar, key=lambda r: r.num_limbs))))
    if len(planar) < len(kinds):
        columns.update(dict.fromkeys(spatial_outcome_columns()))
    return list(columns)


def outcome_columns(parameter_names):
    """The outcome columns of a row, named as in pcr's JSON report (SI units), in order."""
    columns = []
    for s in _TABLE3_SETS:
        for quantity in ("e_p_m", "e_theta_rad"):
            columns += [f"table3.{s}.{quantity}.{stat}" for stat in ("max", "mean")]
        columns += [f"table3.{s}.failed", f"table3.{s}.branch_mismatches"]
    for path in _PATHS:
        for model in _MODELS:
            for stat in _ISO_STATS:
                columns += [f"accuracy.{path}.{model}.{stat}.{s}" for s in ("max", "mean")]
    for name in parameter_names:
        columns += [f"parameters.{name}.error", f"parameters.{name}.std"]
    columns += ["configurations.calibration", "configurations.validation",
                "configurations.unreachable", "calibration.iterations",
                "calibration.load_identified"]
    columns += [f"time.{t}_s" for t in _TIMES] + ["time_s"]
    return columns


# The robots a study names without a file.
BUILTIN_ROBOTS = {"default": lambda: pcr.Robot.default(),
                  "continuum-stewart-gough": lambda: pcr.SpatialRobot.reference()}


def load_robot(name):
    """The robot of factor ``robot``: a built-in one's name, or a robot file (planar or
    spatial)."""
    return BUILTIN_ROBOTS[name]() if name in BUILTIN_ROBOTS else pcr.Robot.load(name)


def _robot(factors, robots):
    name = factors["robot"]
    if name in robots:
        return pcr.Robot.from_json(robots[name], source=name)
    return load_robot(name)


def _with_tolerances(robot, factors):
    """The design with the factors' tolerances as its uncertainty intervals."""
    out = robot.copy()
    u = out.uncertainty if out.uncertainty is not None else pcr.Uncertainty()
    for limb in list(u.limbs) + [u.global_]:
        if factors["mount_tolerance"] is not None:
            limb.A = (factors["mount_tolerance"],) * 2
            limb.B = (factors["mount_tolerance"],) * 2
        if factors["angle_tolerance"] is not None:
            limb.alpha = limb.beta = limb.gamma = factors["angle_tolerance"]
        if factors["length_tolerance"] is not None:
            limb.l = factors["length_tolerance"]
    if factors["diameter_tolerance"] is not None:
        u.global_.d = factors["diameter_tolerance"]
        for limb in u.limbs:
            limb.d = 0.0
    out.uncertainty = u
    return out


def _with_attachment_scale(robot, scale):
    """The spatial design with its attachments' half-widths (A, B, the base and tip turns: the
    file's uncertainty fields, docs/formats.md) times `scale`, at the top level and per rod."""
    if scale is None:
        return robot
    data = json.loads(robot.to_json())
    u = data.get("uncertainty")
    if u is None:
        raise ValueError(f"attachment_scale: the robot {robot.name!r} has no uncertainty section")
    for section in [u] + list(u.get("rods", [])):
        for key in ("A", "B", "base_rotation", "tip_rotation"):
            if key in section:
                section[key] = [scale * h for h in section[key]]
    return pcr.SpatialRobot.from_json(json.dumps(data), source=robot.name)


def _exactly(robot):
    """The same robot without uncertainty: a VirtualRobot of it has it as its truth."""
    out = robot.copy()
    out.uncertainty = None
    return out


def _measured_mounts(design, truth, half_width, rng):
    """The nominal model when the mounts are measured: the truth's A and B plus U(-h, h), the
    rest as designed; its uncertainty intervals hold the truth."""
    out = design.copy()
    u = out.uncertainty
    for i, limb in enumerate(out.limbs):
        limb.A = np.asarray(truth.limbs[i].A) + rng.uniform(-half_width, half_width, 2)
        limb.B = np.asarray(truth.limbs[i].B) + rng.uniform(-half_width, half_width, 2)
    for limb in list(u.limbs) + [u.global_]:
        limb.A = limb.B = (half_width, half_width)
    out.uncertainty = u
    return out


def _put(row, prefix, tree):
    """Flattens the nested dict `tree` into row[prefix.key.subkey] for the keys row has."""
    for key, value in tree.items():
        name = f"{prefix}.{key}"
        if isinstance(value, dict):
            _put(row, name, value)
        elif name in row:
            row[name] = value


class _Stages:
    """Times the stages of a trial into row["time.<stage>_s"]; `current` names the stage a
    failure happened in."""

    def __init__(self, row):
        self.row, self.current, self.start = row, "design", time.perf_counter()

    def enter(self, stage):
        now = time.perf_counter()
        if self.current in _TIMES:
            self.row[f"time.{self.current}_s"] = now - self.start
        self.current, self.start = stage, now


def run_trial(factors, seed, robots=None):
    """One trial: the outcome columns of ``outcome_columns`` for the factors (a dict over FACTORS;
    missing ones take their defaults) and the seed, which alone draws everything random: the
    truth, the measured mounts, the configurations, the camera noise and the unmodelled effects.

    Never raises for a failing trial: ``failure`` names the stage and the reason ("calibration:
    ...") and the outcomes it did not reach are NaN. robots: robot JSON texts by the name of
    factor ``robot`` (the study sends them, so that workers need not read the files).
    """
    factors = factor_values({k: check_factor(k, v, "run_trial") for k, v in factors.items()})
    start = time.perf_counter()
    row = {"failure": None}
    stages = _Stages(row)
    try:
        design = _robot(factors, robots or {})
        row.update(dict.fromkeys(robot_columns(design), math.nan))
        given = {k: v for k, v in factors.items() if v is not None}
        check_applicable(given, design)
        spatial = isinstance(design, pcr.SpatialRobot)
        failure = (_run_spatial if spatial else _run)(factors, seed, design, row, stages)
        if failure:
            row["failure"] = failure
    except Exception as e:  # every failure is a row, its reason naming the stage
        row["failure"] = f"{stages.current}: {type(e).__name__}: {e}"
    stages.enter(None)
    row["time_s"] = time.perf_counter() - start
    return row


def _run(factors, seed, design, row, stages):
    """The trial's stages, filling `row`; returns the reason of a failure found without an
    exception (a calibration stage that did not converge), else None."""
    truth_seed, mounts_seed, sampling_seed, camera_seed = (
        int(s) for s in np.random.SeedSequence(seed).generate_state(4, dtype=np.uint64))

    toleranced = _with_tolerances(design, factors)
    truth = pcr.VirtualRobot(toleranced, seed=truth_seed).truth
    if factors["mount_measurement"] > 0:
        nominal = _measured_mounts(toleranced, truth, factors["mount_measurement"],
                                   np.random.default_rng(mounts_seed))
    else:
        nominal = toleranced
    force = (factors["load_force_x"], factors["load_force_y"])
    camera = dict(seed=camera_seed, misalignments=factors["misalignment"] > 0,
                  misalignment_half_width=factors["misalignment"],
                  unequal_diameters=factors["diameter_spread"] > 0,
                  diameter_half_width=factors["diameter_spread"],
                  force=force if any(force) else None, moment=factors["load_moment"])
    for name in ("noise_position", "noise_angle"):
        if factors[name] is not None:
            camera[name] = factors[name]
    robot = pcr.VirtualRobot(_exactly(truth), **camera)

    # The method itself is the library's (pcr.run_method, as pcr demo runs it): the trial only
    # makes its robots and reduces the result to a row.
    counts = dict(validation_count=factors["validation_count"])
    if factors["calibration_count"] is not None:
        counts["count"] = factors["calibration_count"]
    method = pcr.run_method(nominal, robot, design=factors["design"], seed=sampling_seed,
                            model=factors["model"], repeat=factors["repeat"], sensitivity=False,
                            workspace_map=False, on_stage=stages.enter, drop_unreachable=True,
                            **counts)
    result = method.calibration
    for name in ("calibration", "validation"):
        row[f"configurations.{name}"] = len(method.measured[name][0])
    row["configurations.unreachable"] = method.unmeasured

    row["calibration.iterations"] = sum(s.iterations for s in result.stages)
    row["calibration.load_identified"] = float(result.load_identified)
    # compared in the same frames
    for p, true_value in zip(result.parameters, method.truth_in_gauge.parameters):
        row[f"parameters.{p.name}.error"] = p.value - true_value
        row[f"parameters.{p.name}.std"] = p.std_dev
    _put(row, "table3", result.to_dict(method.table)["table3"])
    for (path_name, model_name), evaluation in method.accuracy.items():
        _put(row, f"accuracy.{path_name}.{model_name}", evaluation.iso.summary)

    unusable = [s for s in result.stages if not s.usable]
    if unusable:
        return ("calibration: stage " + ", ".join(repr(s.name) for s in unusable) +
                " did not converge: " + unusable[0].termination)
    return None


def _run_spatial(factors, seed, design, row, stages):
    """_run for a spatial robot: pcr.run_spatial_method on a SpatialVirtualRobot drawn inside the
    (scaled) intervals of the design, which is the nominal model."""
    truth_seed, _, sampling_seed, _ = (
        int(s) for s in np.random.SeedSequence(seed).generate_state(4, dtype=np.uint64))
    nominal = _with_attachment_scale(design, factors["attachment_scale"])
    camera = dict(seed=truth_seed, payload=factors["payload"],
                  misalignment_half_width=factors["misalignment"],
                  diameter_half_width=factors["diameter_spread"])
    for name in ("noise_position", "noise_angle", "rod_density"):
        if factors[name] is not None:
            camera[name] = factors[name]
    robot = pcr.SpatialVirtualRobot(nominal, **camera)
    row["noise.position_m"], row["noise.angle_rad"] = robot.noise_position, robot.noise_angle
    row["noise.floor_position_m"] = math.sqrt(3.0) * robot.noise_position
    row["noise.floor_angle_rad"] = math.sqrt(3.0) * robot.noise_angle

    counts = dict(validation_count=factors["validation_count"])
    if factors["calibration_count"] is not None:
        counts["count"] = factors["calibration_count"]
    method = pcr.run_spatial_method(nominal, robot, design=factors["design"], seed=sampling_seed,
                                    model=factors["model"], repeat=factors["repeat"],
                                    sensitivity=False, on_stage=stages.enter, **counts)
    for name in ("calibration", "validation"):
        row[f"configurations.{name}"] = len(method.measured[name][0])
    row["configurations.unreachable"] = method.unmeasured

    result = method.calibration
    report = json.loads(result["report_json"])
    row["calibration.iterations"] = sum(s["iterations"] for s in result["stages"])
    row["calibration.load_identified"] = float(result["load_identified"])
    row["calibration.residual_variance"] = result["residual_variance"]
    row["calibration.free_parameters"] = result["free_count"]
    row["calibration.jacobian_rank"] = result["jacobian_rank"]
    row["calibration.at_bound"] = sum(p["at_bound"] for p in result["parameters"])
    _put(row, "table3", report["pose_errors"])
    for (path_name, model_name), evaluation in method.accuracy.items():
        _put(row, f"accuracy.{path_name}.{model_name}", evaluation)

    unusable = [s for s in result["stages"] if not s["usable"]]
    if unusable:
        return ("calibration: stage " + ", ".join(repr(s["name"]) for s in unusable) +
                " did not converge: " + unusable[0]["termination"])
    return None
