"""Type stubs of the pcr._pcr extension module (SI units: m, rad, N, Pa)."""
from __future__ import annotations

import os
from typing import Any, Callable, Literal, Optional, Sequence, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str
has_calibration: bool
has_vision: bool

ArrayLike = npt.ArrayLike
FloatArray = npt.NDArray[np.float64]
# A file's path: str or any os.PathLike (pathlib.Path); a missing input: FileNotFoundError.
StrPath = Union[str, os.PathLike[str]]
# A fixed number of finite numbers (a sequence or a 1-D array): force (fx, fy) N, a centre
# (x, y) m, ... A wrong count or a NaN raises ValueError naming the argument.
Vector = Union[Sequence[float], npt.NDArray[np.floating[Any]]]

class Pose:
    x: float  # m
    y: float  # m
    theta: float  # rad
    def __init__(self, x: float = 0.0, y: float = 0.0, theta: float = 0.0) -> None: ...
    def to_array(self) -> FloatArray: ...
    def inverse(self) -> Pose: ...
    def __mul__(self, other: Pose) -> Pose: ...
    def replace(self, **changes: Any) -> Pose: ...
    def __len__(self) -> int: ...  # 3: x, y, theta = pose
    def __getitem__(self, index: int) -> float: ...
    def __array__(self, dtype: Any = None, copy: Any = None) -> FloatArray: ...  # [x, y, theta]

def compose_poses(a: ArrayLike, b: ArrayLike) -> FloatArray: ...  # rows of (x m, y m, theta rad)

class Limb:
    @property
    def A(self) -> FloatArray: ...  # (2,) m, in W at q = 0 (a view: limb.A[0] = x edits it)
    @A.setter
    def A(self, value: Vector) -> None: ...  # 2 numbers
    alpha: float  # rad
    gamma: float  # rad
    @property
    def B(self) -> FloatArray: ...  # (2,) m, in P
    @B.setter
    def B(self, value: Vector) -> None: ...  # 2 numbers
    beta: float  # rad
    l: float  # m
    d: float  # m
    E: float  # Pa
    precurvature: float  # 1/m: intrinsic curvature u*(0) of a rod shape-set to a curve
    precurvature_slope: float  # 1/m^2: u*(s) = precurvature + precurvature_slope s
    diameter_slope: float  # m/m: a tapered rod's d(s) = d + diameter_slope s
    q_range: tuple[float, float]  # m
    home_bow: Optional[str]  # 'left', 'right' or None: which home a pre-stressed robot is in
    @property
    def EI(self) -> float: ...  # N m^2
    def __init__(self) -> None: ...
    def replace(self, **changes: Any) -> Limb: ...

class Extrinsics:
    camera: Pose  # ^W T_Se
    pattern: Pose  # ^M T_P
    def __init__(self) -> None: ...
    def platform_from_measurement(self, camera_T_pattern: Pose) -> Pose: ...
    def measurement_from_platform(self, world_T_platform: Pose) -> Pose: ...
    def replace(self, **changes: Any) -> Extrinsics: ...

class LimbUncertainty:
    @property
    def A(self) -> FloatArray: ...  # (2,) m
    @A.setter
    def A(self, value: Vector) -> None: ...  # 2 numbers
    alpha: float
    gamma: float
    @property
    def B(self) -> FloatArray: ...  # (2,) m
    @B.setter
    def B(self, value: Vector) -> None: ...  # 2 numbers
    beta: float
    l: float
    d: float
    E: float
    precurvature: float  # 1/m
    def __init__(self) -> None: ...
    def replace(self, **changes: Any) -> LimbUncertainty: ...

class Uncertainty:
    global_: LimbUncertainty
    limbs: list[LimbUncertainty]
    @property
    def camera(self) -> FloatArray: ...  # (3,) m, m, rad
    @camera.setter
    def camera(self, value: Vector) -> None: ...  # 3 numbers
    @property
    def pattern(self) -> FloatArray: ...  # (3,) m, m, rad
    @pattern.setter
    def pattern(self, value: Vector) -> None: ...  # 3 numbers
    def __init__(self) -> None: ...
    def replace(self, **changes: Any) -> Uncertainty: ...

class SolveStatus:
    converged: SolveStatus
    max_iterations: SolveStatus
    singular: SolveStatus
    bifurcation: SolveStatus
    non_finite: SolveStatus
    out_of_range: SolveStatus
    unstable: SolveStatus
    inaccurate: SolveStatus
    unsupported: SolveStatus
    invalid_input: SolveStatus
    @property
    def name(self) -> str: ...
    @property
    def value(self) -> int: ...

class SolverOptions:
    rod_steps: int
    position_accuracy: float
    angle_accuracy: float
    min_rod_steps: int
    max_rod_steps: int
    max_iterations: int
    tolerance: float
    chord_output_share: float
    max_line_search: int
    continuation: bool
    max_continuation_steps: int
    max_continuation_iterations: int
    min_continuation_step: float
    check_stability: bool
    stable_inverse: bool
    through_folds: bool
    max_arclength_steps: int
    def __init__(self) -> None: ...
    def replace(self, **changes: Any) -> SolverOptions: ...

class Solution:
    @property
    def q(self) -> FloatArray: ...  # (n,) m
    @property
    def pose(self) -> Pose: ...
    @property
    def wrenches(self) -> FloatArray: ...  # (n, 3) N, N, N m
    @property
    def converged(self) -> bool: ...
    @property
    def status(self) -> str: ...
    @property
    def status_code(self) -> SolveStatus: ...
    @property
    def iterations(self) -> int: ...
    @property
    def residual_evaluations(self) -> int: ...
    @property
    def residual(self) -> float: ...
    @property
    def max_strain(self) -> float: ...
    @property
    def rod_steps(self) -> int: ...
    @property
    def position_error_estimate(self) -> float: ...
    @property
    def angle_error_estimate(self) -> float: ...
    @property
    def continuation_steps(self) -> int: ...
    @property
    def stable(self) -> Optional[bool]: ...
    @property
    def stability_margin(self) -> float: ...
    @property
    def singularity(self) -> float: ...
    @property
    def shapes(self) -> Optional[list[FloatArray]]: ...  # per rod (steps + 1, 4): s, x, y, theta

class BatchResult:
    q: FloatArray  # (N, n) m
    pose: FloatArray  # (N, 3)
    wrenches: FloatArray  # (N, n, 3)
    converged: npt.NDArray[np.bool_]
    status: npt.NDArray[np.str_]
    status_code: npt.NDArray[np.int32]
    iterations: npt.NDArray[np.int32]
    residual_evaluations: npt.NDArray[np.int32]
    residual: FloatArray
    max_strain: FloatArray
    rod_steps: npt.NDArray[np.int32]
    stable: npt.NDArray[np.bool_]
    stability_margin: FloatArray
    singularity: FloatArray
    position_error_estimate: FloatArray  # m
    angle_error_estimate: FloatArray  # rad
    shapes: Optional[list[Optional[list[FloatArray]]]]
    def __len__(self) -> int: ...

class Robot:
    name: str
    E: float  # Pa
    limbs: list[Limb]
    extrinsics: Extrinsics
    uncertainty: Optional[Uncertainty]
    @property
    def num_limbs(self) -> int: ...
    @property
    def parameters(self) -> FloatArray: ...  # (11 n + 6,) in parameter_names order
    def __init__(self) -> None: ...
    @staticmethod
    def default() -> Robot: ...
    # A file's "kind" says which: a SpatialRobot for "spatial" (typed code: SpatialRobot.load).
    @staticmethod
    def load(path: StrPath) -> Union[Robot, SpatialRobot]: ...
    @staticmethod
    def from_json(text: str, source: str = "<string>") -> Union[Robot, SpatialRobot]: ...
    def save(self, path: StrPath) -> None: ...
    def to_json(self) -> str: ...
    def copy(self) -> Robot: ...
    def replace(self, **changes: Any) -> Robot: ...
    def with_limb(self, index: int, **changes: Any) -> Robot: ...
    @overload
    def forward(self, q: Sequence[float], *, warm_start: Optional[Solution] = None,
                shapes: bool = False, force: Vector = (0.0, 0.0), moment: float = 0.0,
                options: Optional[SolverOptions] = None, path: bool = False) -> Solution: ...
    @overload
    def forward(self, q: ArrayLike, *, warm_start: Optional[Solution] = None,
                shapes: bool = False, force: Vector = (0.0, 0.0), moment: float = 0.0,
                options: Optional[SolverOptions] = None,
                path: bool = False) -> Union[Solution, BatchResult]: ...
    @overload
    def inverse(self, pose: Pose, *, warm_start: Optional[Solution] = None,
                shapes: bool = False, force: Vector = (0.0, 0.0), moment: float = 0.0,
                options: Optional[SolverOptions] = None, path: bool = False) -> Solution: ...
    @overload
    def inverse(self, pose: ArrayLike, *, warm_start: Optional[Solution] = None,
                shapes: bool = False, force: Vector = (0.0, 0.0), moment: float = 0.0,
                options: Optional[SolverOptions] = None,
                path: bool = False) -> Union[Solution, BatchResult]: ...
    # forward/inverse of an (N, k) array, typed (forward(ndarray) cannot tell 1-D from 2-D).
    def forward_batch(self, q: ArrayLike, *, warm_start: Optional[Solution] = None,
                      shapes: bool = False, force: Vector = (0.0, 0.0), moment: float = 0.0,
                      options: Optional[SolverOptions] = None,
                      path: bool = False) -> BatchResult: ...
    def inverse_batch(self, pose: ArrayLike, *, warm_start: Optional[Solution] = None,
                      shapes: bool = False, force: Vector = (0.0, 0.0), moment: float = 0.0,
                      options: Optional[SolverOptions] = None,
                      path: bool = False) -> BatchResult: ...
    def home(self, *, shapes: bool = False, force: Vector = (0.0, 0.0), moment: float = 0.0,
             options: Optional[SolverOptions] = None) -> Solution: ...
    def with_home_at(self, pose: Pose, *, force: Vector = (0.0, 0.0), moment: float = 0.0,
                     options: Optional[SolverOptions] = None) -> Robot: ...
    # When has_calibration. q: a Solution (no FK solve), n joint values, or (N, n) (every value
    # then an array over the rows). Keys: status, ok, pose, covariance (3, 3), position_1sigma,
    # position_3sigma (m), position_axis (2,), orientation_1sigma, orientation_3sigma (rad),
    # worst_components (3,), worst_position (m), worst_position_direction (2,),
    # worst_orientation (rad).
    def predicted_accuracy(self, q: Union[Solution, ArrayLike],
                           covariance: Optional[ParameterCovariance] = None, *,
                           frame: Literal["platform", "measurement"] = "platform",
                           measurement_covariance: Optional[ArrayLike] = None,
                           worst_case: bool = True, force: Vector = (0.0, 0.0),
                           moment: float = 0.0,
                           options: Optional[SolverOptions] = None) -> dict[str, Any]: ...

# ---- spatial robots (pcr/spatial/, a robot file with "kind": "spatial") ---------------------
# Quaternions are (w, x, y, z), body -> parent; rotation vectors angle (rad) times axis.

class SpatialLimb:
    length: float  # m (a rod pushed through its hole: the free length at q = 0)
    diameter: float  # m
    young_modulus: float  # Pa
    shear_modulus: float  # Pa
    density: float  # kg/m^3
    shear_and_extension: bool
    actuation: str  # 'length_through_hole' or 'translated_clamp'
    attachment: str  # 'clamped' or 'spherical'
    @property
    def intrinsic_curvature(self) -> FloatArray: ...  # (3,) 1/m (a view)
    @intrinsic_curvature.setter
    def intrinsic_curvature(self, value: Vector) -> None: ...
    @property
    def A(self) -> FloatArray: ...  # (3,) m, in W
    @A.setter
    def A(self, value: Vector) -> None: ...
    @property
    def base_orientation(self) -> FloatArray: ...  # (4,) unit quaternion, rod frame at A -> W
    @base_orientation.setter
    def base_orientation(self, value: Vector) -> None: ...
    @property
    def actuator_direction(self) -> FloatArray: ...  # (3,) unit, in W
    @actuator_direction.setter
    def actuator_direction(self, value: Vector) -> None: ...
    @property
    def B(self) -> FloatArray: ...  # (3,) m, in P
    @B.setter
    def B(self, value: Vector) -> None: ...
    @property
    def tip_orientation(self) -> FloatArray: ...  # (4,) unit quaternion, tip frame -> P
    @tip_orientation.setter
    def tip_orientation(self, value: Vector) -> None: ...
    @property
    def EI(self) -> float: ...  # N m^2
    def __init__(self) -> None: ...
    def replace(self, **changes: Any) -> SpatialLimb: ...

class SpatialSolution:
    @property
    def q(self) -> FloatArray: ...  # (n,) m
    @property
    def position(self) -> FloatArray: ...  # (3,) m, P's origin in W
    @property
    def quaternion(self) -> FloatArray: ...  # (4,) w, x, y, z (w >= 0), P -> W
    @property
    def rotation(self) -> FloatArray: ...  # (3, 3) P -> W
    @property
    def rotation_vector(self) -> FloatArray: ...  # (3,) rad, the rx, ry, rz of `pcr fk`
    @property
    def wrenches(self) -> FloatArray: ...  # (n, 6) proximal force N, moment N m, in W
    @property
    def converged(self) -> bool: ...
    @property
    def status(self) -> str: ...
    @property
    def status_code(self) -> SolveStatus: ...
    @property
    def iterations(self) -> int: ...
    @property
    def residual_evaluations(self) -> int: ...
    @property
    def residual(self) -> float: ...
    @property
    def max_strain(self) -> float: ...
    @property
    def rod_steps(self) -> int: ...
    @property
    def position_error_estimate(self) -> float: ...
    @property
    def angle_error_estimate(self) -> float: ...
    @property
    def continuation_steps(self) -> int: ...
    @property
    def stable(self) -> Optional[bool]: ...
    @property
    def stability_margin(self) -> float: ...
    @property
    def singularity(self) -> float: ...
    @property
    def shapes(self) -> Optional[list[FloatArray]]: ...  # per rod (steps + 1, 8): s, x, y, z, w, qx, qy, qz

class SpatialBatchResult:
    q: FloatArray  # (N, n) m
    position: FloatArray  # (N, 3) m
    quaternion: FloatArray  # (N, 4) w, x, y, z (w >= 0)
    rotation: FloatArray  # (N, 3, 3)
    rotation_vector: FloatArray  # (N, 3) rad
    wrenches: FloatArray  # (N, n, 6) N, N m
    converged: npt.NDArray[np.bool_]
    status: npt.NDArray[np.str_]
    status_code: npt.NDArray[np.int32]
    iterations: npt.NDArray[np.int32]
    residual_evaluations: npt.NDArray[np.int32]
    residual: FloatArray
    max_strain: FloatArray
    rod_steps: npt.NDArray[np.int32]
    stable: npt.NDArray[np.bool_]
    stability_margin: FloatArray
    singularity: FloatArray
    position_error_estimate: FloatArray  # m
    angle_error_estimate: FloatArray  # rad
    shapes: Optional[list[Optional[list[FloatArray]]]]
    def __len__(self) -> int: ...

class SpatialRobot:
    name: str
    rods: list[SpatialLimb]
    platform_mass: float  # kg
    @property
    def num_rods(self) -> int: ...
    @property
    def platform_centre_of_mass(self) -> FloatArray: ...  # (3,) m, in P (a view)
    @platform_centre_of_mass.setter
    def platform_centre_of_mass(self, value: Vector) -> None: ...
    @property
    def gravity(self) -> FloatArray: ...  # (3,) m/s^2, in W
    @gravity.setter
    def gravity(self, value: Vector) -> None: ...
    @property
    def external_force(self) -> FloatArray: ...  # (3,) N, in W, at P's origin
    @external_force.setter
    def external_force(self, value: Vector) -> None: ...
    @property
    def external_moment(self) -> FloatArray: ...  # (3,) N m, in W
    @external_moment.setter
    def external_moment(self, value: Vector) -> None: ...
    def __init__(self) -> None: ...
    @staticmethod
    def reference() -> SpatialRobot: ...
    @staticmethod
    def load(path: StrPath) -> SpatialRobot: ...
    @staticmethod
    def from_json(text: str, source: str = "<string>") -> SpatialRobot: ...
    def save(self, path: StrPath) -> None: ...
    def to_json(self) -> str: ...
    def copy(self) -> SpatialRobot: ...
    def replace(self, **changes: Any) -> SpatialRobot: ...
    @overload
    def forward(self, q: Sequence[float], *, warm_start: Optional[SpatialSolution] = None,
                shapes: bool = False, options: Optional[SolverOptions] = None,
                path: bool = False) -> SpatialSolution: ...
    @overload
    def forward(self, q: ArrayLike, *, warm_start: Optional[SpatialSolution] = None,
                shapes: bool = False, options: Optional[SolverOptions] = None,
                path: bool = False) -> Union[SpatialSolution, SpatialBatchResult]: ...
    # The orientation at most once, by keyword (none: the identity); (N, ...) rows -> a batch.
    def inverse(self, position: ArrayLike, *, rotation: Optional[ArrayLike] = None,
                quaternion: Optional[ArrayLike] = None,
                rotation_vector: Optional[ArrayLike] = None,
                warm_start: Optional[SpatialSolution] = None, shapes: bool = False,
                options: Optional[SolverOptions] = None,
                path: bool = False) -> Union[SpatialSolution, SpatialBatchResult]: ...
    def forward_batch(self, q: ArrayLike, *, warm_start: Optional[SpatialSolution] = None,
                      shapes: bool = False, options: Optional[SolverOptions] = None,
                      path: bool = False) -> SpatialBatchResult: ...
    def inverse_batch(self, position: ArrayLike, *, rotation: Optional[ArrayLike] = None,
                      quaternion: Optional[ArrayLike] = None,
                      rotation_vector: Optional[ArrayLike] = None,
                      warm_start: Optional[SpatialSolution] = None, shapes: bool = False,
                      options: Optional[SolverOptions] = None,
                      path: bool = False) -> SpatialBatchResult: ...
    def home(self, *, shapes: bool = False,
             options: Optional[SolverOptions] = None) -> SpatialSolution: ...

# ---- calibration (when has_calibration) ----------------------------------------------------
class VirtualRobot:
    def __init__(self, nominal: Robot, *, seed: int = 1, noise_position: float = 9.13e-9,
                 noise_angle: float = 1.2e-6, misalignments: bool = False,
                 misalignment_half_width: float = 5e-3, unequal_diameters: bool = False,
                 diameter_half_width: float = 2e-6, force: Optional[Vector] = None,
                 moment: float = 0.0, options: Optional[SolverOptions] = None) -> None: ...
    @property
    def nominal(self) -> Robot: ...
    @property
    def truth(self) -> Robot: ...
    @property
    def load(self) -> tuple[FloatArray, float]: ...
    def measure(self, q: ArrayLike) -> dict[str, Any]: ...
    def measure_dataset(self, q: ArrayLike) -> dict[str, Any]: ...
    def return_home(self) -> None: ...

def parameter_names(num_limbs: int) -> list[str]: ...
def sensitivity_configurations(robot: Robot, step: float = 1e-3,
                               centre: Optional[Vector] = None) -> FloatArray: ...
def platform_parameter_jacobian(robot: Robot, q: ArrayLike, *, force: Vector = (0.0, 0.0),
                                moment: float = 0.0,
                                options: Optional[SolverOptions] = None) -> Optional[FloatArray]: ...
def sensitivity(robot: Robot, *, step: float = 1e-3, centre: Optional[Vector] = None,
                force: Vector = (0.0, 0.0), moment: float = 0.0,
                options: Optional[SolverOptions] = None) -> dict[str, Any]: ...
def read_dataset(path: StrPath, num_joints: int = -1) -> tuple[FloatArray, FloatArray]: ...
def write_dataset(path: StrPath, q: ArrayLike, measured: ArrayLike) -> None: ...
def read_configurations(path: StrPath, num_joints: int = -1) -> FloatArray: ...
def write_configurations(path: StrPath, q: ArrayLike) -> None: ...
def admissible_configuration(robot: Robot, q: ArrayLike, strain_limit: float = 0.01) -> bool: ...
def poisson_disc_sample(robot: Robot, *, count: int = 99, seed: int = 1,
                        min_distance: float = 0.0, box_min: Optional[ArrayLike] = None,
                        box_max: Optional[ArrayLike] = None, strain_limit: float = 0.01,
                        attempts: int = 30, force: Vector = (0.0, 0.0),
                        moment: float = 0.0) -> dict[str, Any]: ...
def sample_configurations(robot: Robot, *, count: int = 99, validation_count: int = 0,
                          design: Literal["poisson-disc", "d-optimal"] = "poisson-disc",
                          candidates: int = 0, seed: int = 1, min_distance: float = 0.0,
                          box_min: Optional[ArrayLike] = None, box_max: Optional[ArrayLike] = None,
                          strain_limit: float = 0.01, attempts: int = 30,
                          force: Vector = (0.0, 0.0), moment: float = 0.0) -> dict[str, Any]: ...
def default_stages() -> list[dict[str, Any]]: ...
def load_calibration_stages(path: StrPath) -> list[dict[str, Any]]: ...
def with_load_stage(stages: Union[Sequence[dict[str, Any]], StrPath]) -> list[dict[str, Any]]: ...
def pose_errors(robot: Robot, q: ArrayLike, measured: ArrayLike, *, force: Vector = (0.0, 0.0),
                moment: float = 0.0) -> dict[str, float]: ...
def pose_errors_per_configuration(
        robot: Robot, q: ArrayLike, measured: ArrayLike, *, force: Vector = (0.0, 0.0),
        moment: float = 0.0, options: Optional[SolverOptions] = None,
        path: bool = True) -> tuple[FloatArray, FloatArray]: ...  # e_p m, e_theta rad

# Defaults: the C++ CalibrationOptions' (a new one holds them). A bad value: ValueError naming
# the field and the value.
class CalibrationOptions:
    @property
    def stages(self) -> list[dict[str, Any]]: ...  # a copy: assign to change
    @stages.setter
    def stages(self, value: Union[StrPath, Sequence[dict[str, Any]]]) -> None: ...
    orientation_weight: float  # m/rad, >= 0
    residual_scale: float  # m, > 0
    derivatives: Literal["implicit", "numeric", "autodiff"]
    fk: SolverOptions
    max_iterations: int  # per stage, >= 1
    fix_gauge: bool
    gauge_prior_weight: float
    stage_gauge: Literal["subspace", "prior"]
    function_tolerance: float
    intermediate_function_tolerance: float
    compute_covariance: bool
    robust_scale: float  # declared noise units, >= 0 (0: plain least squares)
    drop_unreachable: bool
    def __init__(self) -> None: ...
    def replace(self, **changes: Any) -> CalibrationOptions: ...

class StageReport:
    @property
    def name(self) -> str: ...
    @property
    def free_parameters(self) -> list[str]: ...
    @property
    def initial_cost(self) -> float: ...  # m^2
    @property
    def final_cost(self) -> float: ...  # m^2
    @property
    def iterations(self) -> int: ...
    @property
    def time_s(self) -> float: ...
    @property
    def termination(self) -> str: ...
    @property
    def usable(self) -> bool: ...
    @property
    def residual_evaluations(self) -> int: ...
    @property
    def jacobian_evaluations(self) -> int: ...
    @property
    def residual_time_s(self) -> float: ...
    @property
    def jacobian_time_s(self) -> float: ...
    @property
    def linear_solver_time_s(self) -> float: ...
    @property
    def fk_solves(self) -> int: ...
    @property
    def fk_warm_start_failures(self) -> int: ...
    @property
    def fk_newton_iterations(self) -> int: ...

class ParameterEstimate:
    @property
    def name(self) -> str: ...  # 'l[1]', 'camera_x', 'load_f_x', ...
    @property
    def kind(self) -> str: ...  # 'l', 'A_x', 'camera_theta', ...
    @property
    def nominal(self) -> float: ...
    @property
    def value(self) -> float: ...
    @property
    def std_dev(self) -> float: ...  # 0: held; NaN: not identifiable or not computed
    @property
    def half_width(self) -> float: ...
    @property
    def free(self) -> bool: ...
    @property
    def gauge_reference(self) -> bool: ...
    @property
    def box_deviation(self) -> float: ...  # in bounds_scale half-widths; NaN: unbounded
    @property
    def at_bound(self) -> bool: ...
    @property
    def identifiable(self) -> bool: ...

class GaugeDirection:
    @property
    def name(self) -> str: ...
    @property
    def combination(self) -> str: ...
    @property
    def relative_gain(self) -> float: ...
    @property
    def free(self) -> bool: ...
    @property
    def present(self) -> bool: ...

class PoseErrorStats:
    @property
    def max_p(self) -> float: ...  # m, Eq. 8
    @property
    def mean_p(self) -> float: ...
    @property
    def min_p(self) -> float: ...
    @property
    def max_theta(self) -> float: ...  # rad, Eq. 9
    @property
    def mean_theta(self) -> float: ...
    @property
    def min_theta(self) -> float: ...
    @property
    def count(self) -> int: ...
    @property
    def failed(self) -> int: ...
    @property
    def branch_mismatches(self) -> int: ...  # measured next to another equilibrium

class CalibrationTable:
    @property
    def nominal_calibration(self) -> PoseErrorStats: ...
    @property
    def identified_calibration(self) -> PoseErrorStats: ...
    @property
    def nominal_validation(self) -> Optional[PoseErrorStats]: ...  # None without a validation set
    @property
    def identified_validation(self) -> Optional[PoseErrorStats]: ...
    @property
    def has_validation(self) -> bool: ...
    @property
    def warnings(self) -> list[str]: ...
    def to_text(self) -> str: ...

class CalibrationResult:
    @property
    def identified(self) -> Robot: ...
    @property
    def extrinsics_only(self) -> Robot: ...  # the paper's nominal model
    @property
    def stages(self) -> list[StageReport]: ...
    @property
    def parameters(self) -> list[ParameterEstimate]: ...
    @property
    def gauge(self) -> list[GaugeDirection]: ...
    @property
    def load(self) -> tuple[float, float, float]: ...  # f_x N, f_y N, m_z N m
    @property
    def load_identified(self) -> bool: ...
    @property
    def free_count(self) -> int: ...
    @property
    def jacobian_rank(self) -> int: ...
    @property
    def singular_values(self) -> FloatArray: ...
    @property
    def residual_variance(self) -> float: ...
    @property
    def residuals_exceed_noise(self) -> bool: ...
    @property
    def covariance_ok(self) -> bool: ...
    @property
    def covariance(self) -> Optional[ParameterCovariance]: ...  # None without compute_covariance
    @property
    def dropped(self) -> list[str]: ...
    @property
    def outliers(self) -> list[str]: ...
    @property
    def outlier_threshold(self) -> float: ...
    @property
    def unidentifiable(self) -> list[str]: ...
    @property
    def warnings(self) -> list[str]: ...
    # The report pcr_calibrate --report writes; table None: Table 3 on the calibration set alone.
    def in_gauge(self, robot: Robot) -> Robot: ...
    def to_json(self, table: Optional[CalibrationTable] = None) -> str: ...
    def to_dict(self, table: Optional[CalibrationTable] = None) -> dict[str, Any]: ...
    def to_text(self, table: Optional[CalibrationTable] = None) -> str: ...

# options: None for the defaults; `changes` set CalibrationOptions fields of a copy by name
# (TypeError for another name).
def calibrate(nominal: Robot, q: ArrayLike, measured: ArrayLike,
              options: Optional[CalibrationOptions] = None, *,
              progress: Optional[Callable[[str], None]] = None,
              **changes: Any) -> tuple[Robot, CalibrationResult]: ...

# The spatial calibration (pcr/calib/spatial_calibrator.hpp); the result's fields as a dict.
def default_spatial_stages() -> list[dict[str, Any]]: ...
def calibrate_spatial(nominal: SpatialRobot, q: ArrayLike, measured: ArrayLike,
                      validation_q: Optional[ArrayLike] = None,
                      validation_measured: Optional[ArrayLike] = None, *,
                      stages: Optional[Union[Sequence[dict[str, Any]], StrPath]] = None,
                      orientation_weight: float = ..., residual_scale: float = ...,
                      robust_scale: float = 5.0, max_iterations: int = 100,
                      function_tolerance: float = 1e-8, compute_covariance: bool = True,
                      drop_unreachable: bool = False,
                      progress: Optional[Callable[[str], None]] = None
                      ) -> tuple[SpatialRobot, dict[str, Any]]: ...
def simulate_spatial_measurements(nominal: SpatialRobot, q: ArrayLike, *, seed: int = 1,
                                  truth_at_fraction: float = 0.0, noise_position: float = ...,
                                  noise_angle: float = 1.2e-6) -> dict[str, Any]: ...

class ModelSelection:
    @property
    def load_chosen(self) -> bool: ...
    @property
    def tried_load(self) -> bool: ...
    @property
    def rows(self) -> int: ...
    @property
    def mean_difference(self) -> float: ...
    @property
    def t(self) -> float: ...
    @property
    def decision(self) -> str: ...

class SpatialModelSelection:  # ModelSelection's properties, for a spatial robot
    @property
    def load_chosen(self) -> bool: ...
    @property
    def tried_load(self) -> bool: ...
    @property
    def rows(self) -> int: ...
    @property
    def mean_difference(self) -> float: ...
    @property
    def t(self) -> float: ...
    @property
    def decision(self) -> str: ...

MODEL_SELECTION_T: float  # 2.326, one-sided 1 %
# Returns (identified Robot, chosen, the stages' result, the load model's or None, selection).
@overload
def calibrate_selecting_model(
        nominal: Robot, q: ArrayLike, measured: ArrayLike, validation_q: ArrayLike,
        validation_measured: ArrayLike, options: Optional[CalibrationOptions] = None, *,
        progress: Optional[Callable[[str], None]] = None, **changes: Any,
) -> tuple[Robot, CalibrationResult, CalibrationResult, Optional[CalibrationResult],
           ModelSelection]: ...
# A spatial robot: keywords as calibrate_spatial's; the results as its dicts.
@overload
def calibrate_selecting_model(
        nominal: SpatialRobot, q: ArrayLike, measured: ArrayLike, validation_q: ArrayLike,
        validation_measured: ArrayLike, *,
        stages: Optional[Union[Sequence[dict[str, Any]], StrPath]] = None,
        orientation_weight: float = ..., residual_scale: float = ..., robust_scale: float = 5.0,
        max_iterations: int = 100, function_tolerance: float = 1e-8,
        compute_covariance: bool = True, drop_unreachable: bool = False,
        progress: Optional[Callable[[str], None]] = None,
) -> tuple[SpatialRobot, dict[str, Any], dict[str, Any], Optional[dict[str, Any]],
           SpatialModelSelection]: ...
def calibration_table(result: CalibrationResult, q: ArrayLike, measured: ArrayLike,
                      validation_q: Optional[ArrayLike] = None,
                      validation_measured: Optional[ArrayLike] = None) -> CalibrationTable: ...

class ParameterCovariance:
    def __init__(self, names: Sequence[str], matrix: ArrayLike) -> None: ...
    @property
    def names(self) -> list[str]: ...  # parameter_names order, then load_f_x, load_f_y, load_m_z
    @property
    def matrix(self) -> FloatArray: ...  # (p, p) SI; 0 rows: held; NaN rows: not identifiable
    @property
    def num_limbs(self) -> int: ...
    @property
    def has_load(self) -> bool: ...

def read_parameter_covariance(path: StrPath, num_limbs: int = 0) -> ParameterCovariance: ...

# ---- trajectories and ISO 9283 accuracy (when has_calibration) -----------------------------
PAPER_SQUARE_SIDE: float  # 2e-3 m
PAPER_CIRCLE_DIAMETER: float  # 3e-3 m

def square_path(side: float = 2e-3, *, centre: Vector = (0.0, 0.0), rotation: float = 0.0,
                theta: float = 0.0, count: int = 40) -> FloatArray: ...  # (count, 3)
def circle_path(diameter: float = 3e-3, *, centre: Vector = (0.0, 0.0),
                start_angle: float = 0.0, theta: float = 0.0,
                count: int = 36) -> FloatArray: ...  # (count, 3)
def load_path_csv(path: StrPath) -> FloatArray: ...  # (N, 3)
def command_path(robot: Robot, path: ArrayLike, *, strain_limit: float = 0.01,
                 force: Vector = (0.0, 0.0), moment: float = 0.0,
                 options: Optional[SolverOptions] = None,
                 cold_start_fallback: bool = True) -> dict[str, Any]: ...  # q, poses, max_strain, iterations

@overload
def workspace_map(robot: Robot, *, theta: float = 0.0, grid: int = 200,
                  range: Optional[tuple[float, float, float, float]] = None,
                  force: Any = ..., moment: float = 0.0,
                  options: Optional[SolverOptions] = None, threads: int = 0) -> dict[str, Any]: ...
@overload
def workspace_map(robot: SpatialRobot, *,
                  plane: Literal["xy", "xz", "yz", "rxry", "rxrz", "ryrz"] = "xy",
                  pose: Optional[tuple[float, float, float, float, float, float]] = None,
                  range: Optional[tuple[float, float, float, float]] = None, grid: int = 40,
                  stroke: Optional[tuple[float, float]] = None,
                  options: Optional[SolverOptions] = None, threads: int = 0) -> dict[str, Any]: ...
def rotation_range(robot: Robot, x: float, y: float, *, theta: float = 0.0, force: Any = ...,
                   moment: float = 0.0,
                   options: Optional[SolverOptions] = None) -> tuple[bool, float, float]: ...

class Iso9283Result:
    @property
    def commanded(self) -> FloatArray: ...  # (N, 3)
    @property
    def barycentre(self) -> FloatArray: ...  # (N, 3)
    @property
    def cycles(self) -> npt.NDArray[np.int32]: ...
    @property
    def ap_x(self) -> FloatArray: ...  # (N,) m
    @property
    def ap_y(self) -> FloatArray: ...  # (N,) m
    @property
    def ap_p(self) -> FloatArray: ...  # (N,) m, Eq. 10
    @property
    def ap_theta(self) -> FloatArray: ...  # (N,) rad, Eq. 11 (signed)
    @property
    def l_bar(self) -> FloatArray: ...
    @property
    def s_l(self) -> FloatArray: ...
    @property
    def rp_l(self) -> FloatArray: ...  # (N,) m
    @property
    def s_theta(self) -> FloatArray: ...
    @property
    def rp_theta(self) -> FloatArray: ...  # (N,) rad, RP_theta = +-rp_theta
    @property
    def summary(self) -> dict[str, dict[str, float]]: ...  # ap_p, ap_theta_abs, rp_l, rp_theta
    def poses_csv(self) -> str: ...
    def to_json(self, name: str = "result") -> str: ...
    def __len__(self) -> int: ...

def iso9283(commanded: ArrayLike,
            attained: Union[ArrayLike, Sequence[ArrayLike]]) -> Iso9283Result: ...
def iso9283_table(rows: Union[Iso9283Result, dict[str, Iso9283Result],
                              Sequence[tuple[str, Iso9283Result]]]) -> str: ...
def iso9283_json(rows: Union[Iso9283Result, dict[str, Iso9283Result],
                             Sequence[tuple[str, Iso9283Result]]]) -> str: ...

class AccuracyEvaluation:
    @property
    def commanded(self) -> FloatArray: ...  # (N, 3)
    @property
    def q(self) -> FloatArray: ...  # (N, n) m
    @property
    def command(self) -> dict[str, Any]: ...
    @property
    def attained(self) -> FloatArray: ...  # (N, R, 3) ^W T_P, [pose, cycle]
    @property
    def iso(self) -> Iso9283Result: ...
    def __len__(self) -> int: ...

def evaluate_on_virtual_robot(model: Robot, robot: VirtualRobot, path: ArrayLike, *,
                              repeat: int = 30, frame: str = "model", strain_limit: float = 0.01,
                              force: Vector = (0.0, 0.0), moment: float = 0.0,
                              options: Optional[SolverOptions] = None) -> AccuracyEvaluation: ...
def load_measured_csv(path: StrPath) -> tuple[FloatArray, Union[FloatArray, list[FloatArray]]]: ...
def measured_to_csv(commanded: ArrayLike,
                    attained: Union[ArrayLike, Sequence[ArrayLike]]) -> str: ...

# ---- the method as one call (pcr/calib/method.hpp) ---------------------------------------------
class MethodResult:
    @property
    def sensitivity(self) -> Optional[dict[str, Any]]: ...
    @property
    def configurations(self) -> dict[str, FloatArray]: ...
    @property
    def measured(self) -> dict[str, tuple[FloatArray, FloatArray]]: ...
    @property
    def unmeasured(self) -> int: ...
    @property
    def calibration(self) -> CalibrationResult: ...
    @property
    def selection(self) -> Optional[ModelSelection]: ...
    @property
    def table(self) -> CalibrationTable: ...
    @property
    def identified(self) -> Robot: ...
    @property
    def truth_in_gauge(self) -> Robot: ...
    @property
    def accuracy(self) -> dict[tuple[str, str], AccuracyEvaluation]: ...
    @property
    def map(self) -> Optional[dict[str, Any]]: ...
    @property
    def rotation_range(self) -> tuple[bool, float, float]: ...
    @property
    def seconds(self) -> dict[str, float]: ...

def run_method(nominal: Robot, robot: VirtualRobot, options: Optional[CalibrationOptions] = None,
               *, count: int = 99, validation_count: int = 56, design: str = "poisson-disc",
               seed: int = 1, model: str = "selected", repeat: int = 30, square_poses: int = 40,
               circle_poses: int = 36, sensitivity: bool = True, workspace_map: bool = True,
               map_grid: int = 200, on_stage: Optional[Callable[[str], None]] = None,
               progress: Optional[Callable[[str], None]] = None,
               **changes: Any) -> MethodResult: ...

# The method on a virtual spatial robot (pcr/calib/spatial_method.hpp), what pcr demo --robot
# runs for a spatial file.
class SpatialVirtualRobot:
    def __init__(self, nominal: SpatialRobot, *, seed: int = 1, truth_at_fraction: float = 0.0,
                 noise_position: float = ..., noise_angle: float = 1.2e-6, payload: float = 0.0,
                 misalignment_half_width: float = 0.0, diameter_half_width: float = 0.0,
                 rod_density: float = -1.0, options: Optional[SolverOptions] = None) -> None: ...
    @property
    def nominal(self) -> SpatialRobot: ...
    @property
    def truth(self) -> SpatialRobot: ...
    @property
    def noise_position(self) -> float: ...
    @property
    def noise_angle(self) -> float: ...
    def return_home(self) -> None: ...

class SpatialMethodResult:
    @property
    def sensitivity(self) -> Optional[dict[str, Any]]: ...
    @property
    def configurations(self) -> dict[str, FloatArray]: ...
    @property
    def measured(self) -> dict[str, tuple[FloatArray, FloatArray]]: ...
    @property
    def unmeasured(self) -> int: ...
    @property
    def calibration(self) -> dict[str, Any]: ...
    @property
    def selection(self) -> Optional[SpatialModelSelection]: ...
    @property
    def identified(self) -> SpatialRobot: ...
    @property
    def truth(self) -> SpatialRobot: ...
    @property
    def centre(self) -> tuple[FloatArray, FloatArray]: ...
    @property
    def accuracy(self) -> dict[tuple[str, str], dict[str, Any]]: ...
    @property
    def seconds(self) -> dict[str, float]: ...

def run_spatial_method(nominal: SpatialRobot, robot: SpatialVirtualRobot, *, count: int = 99,
                       validation_count: int = 56, design: str = "poisson-disc", seed: int = 1,
                       stages: Optional[Union[Sequence[dict[str, Any]], StrPath]] = None,
                       model: str = "stages",
                       repeat: int = 30, square_poses: int = 40, circle_poses: int = 36,
                       helix_poses: int = 73, sensitivity: bool = True,
                       on_stage: Optional[Callable[[str], None]] = None,
                       progress: Optional[Callable[[str], None]] = None
                       ) -> SpatialMethodResult: ...

# ---- measurement from images (when has_vision) ---------------------------------------------
class Camera:
    width: int  # px
    height: int  # px
    K: FloatArray  # (3, 3) px
    distortion: FloatArray  # OpenCV order k1 k2 p1 p2 [k3 [k4 k5 k6]]
    def __init__(self, width: int, height: int, K: ArrayLike,
                 distortion: Optional[ArrayLike] = None) -> None: ...
    def project(self, point_camera: Vector) -> FloatArray: ...  # 3 numbers (m) -> (2,) px
    def save(self, path: StrPath) -> None: ...

def load_camera(path: StrPath) -> Camera: ...

class MountLayout:
    @property
    def num_limbs(self) -> int: ...
    @property
    def mounts(self) -> list[dict[str, Any]]: ...
    def without_uncertainty(self) -> MountLayout: ...
    @staticmethod
    def from_json(text: str, source: str = "<string>",
                  family: str = "tag36h11") -> MountLayout: ...
    def __len__(self) -> int: ...

def load_mounts(path: StrPath, family: str = "tag36h11") -> MountLayout: ...
def default_mounts() -> MountLayout: ...
def read_image(path: StrPath) -> npt.NDArray[np.float32]: ...  # (H, W) in [0, 1]
def write_png(path: StrPath, image: ArrayLike, bits: int = 8) -> None: ...
def mount_tags(robot: Robot, mounts: MountLayout, platform: Union[Pose, Vector] = (0.0, 0.0, 0.0),
               q: Optional[Sequence[float]] = None) -> list[dict[str, Any]]: ...
def render_robot(robot: Robot, mounts: MountLayout, *, camera: Optional[Camera] = None,
                 height: float = 0.5, tilt_x: float = 0.0, tilt_y: float = 0.0,
                 q: Optional[Sequence[float]] = None,
                 platform: Union[Pose, Vector] = (0.0, 0.0, 0.0),
                 rods: bool = True, supersampling: int = 4, blur: float = 0.0,
                 noise: float = 0.0, gradient: float = 0.0,
                 seed: int = 1) -> npt.NDArray[np.float32]: ...

class RobotMeasurement:
    @property
    def limbs(self) -> list[dict[str, Any]]: ...
    @property
    def corner_rms_px(self) -> float: ...
    @property
    def corner_sigma_px(self) -> float: ...
    @property
    def world_in_plane(self) -> Pose: ...
    @property
    def platform_in_plane(self) -> Pose: ...
    @property
    def registration_rms_A(self) -> float: ...  # m
    @property
    def registration_rms_B(self) -> float: ...  # m
    @property
    def markers(self) -> list[dict[str, Any]]: ...

def measure_robot(image: ArrayLike, mounts: MountLayout, camera: Camera, design: Robot, *,
                  source: str = "<image>", coverage_factor: float = 3.0,
                  min_margin: float = 30.0, max_hamming: int = 0) -> RobotMeasurement: ...
def measured_description(design: Robot, measurement: RobotMeasurement) -> Robot: ...

class SweepResult:
    gamma: float  # rad
    gamma_halfwidth: float  # rad
    direction_plane: float  # rad
    direction_sigma: float  # rad
    @property
    def centres(self) -> npt.NDArray[np.float64]: ...  # (N, 2), m
    line_rms: float  # m

def measure_sweep(images: Sequence[ArrayLike], limb: int, mounts: MountLayout, camera: Camera,
                  home: RobotMeasurement, *, sources: Optional[Sequence[str]] = None,
                  coverage_factor: float = 3.0) -> SweepResult: ...
def render_chessboard(*, camera: Optional[Camera] = None, cols: int = 9, rows: int = 6,
                      square: float = 0.005, board_pose: Union[Pose, Vector] = (0.0, 0.0, 0.0),
                      height: float = 0.5, tilt_x: float = 0.0, tilt_y: float = 0.0,
                      supersampling: int = 4, blur: float = 0.0, noise: float = 0.0,
                      gradient: float = 0.0, seed: int = 1) -> npt.NDArray[np.float32]: ...

class CameraCalibration:
    camera: Camera
    rms_px: float
    used: list[str]
    rejected: list[str]

def calibrate_camera(images: Sequence[StrPath], *, cols: int = 9, rows: int = 6,
                     square: float = 0.005) -> CameraCalibration: ...
