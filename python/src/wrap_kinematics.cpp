// Robot.forward / Robot.inverse / Robot.home, pcr.SolverOptions, pcr.Solution, pcr.BatchResult.
#include <algorithm>
#include <limits>
#include <memory>
#include <tuple>
#include <type_traits>

#include "bindings.hpp"
#include "solve.hpp"
#include "summary.hpp"

namespace pcr::python {

PlatformLoad<double> make_load(const py::handle& force, double moment) {
  return PlatformLoad<double>{to_vector<2>(force, "force", "fx, fy in N"),
                              in_range(moment, PlatformLoad<double>::kMoment)};
}

namespace {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Arrays of a batch: the values, and the summary arrays.
struct BatchResult : SummaryArrays {
  py::array_t<double> q, pose, wrenches;
  /// Every field, in the order of its pickled state.
  auto fields() { return std::tuple_cat(std::tie(q, pose, wrenches), SummaryArrays::fields()); }
};

/// The rods' shapes of a solution: one (steps + 1, 4) array per rod (s, x, y, theta).
py::list rod_shapes(const RobotParams<double>& robot, const JointVector& q,
                    const std::array<Wrench<double>, kMaxLimbs>& wrenches, int rod_steps) {
  const int n = robot.num_limbs;
  std::vector<RowMatrix> shapes(static_cast<std::size_t>(n), RowMatrix(rod_steps + 1, 4));
  std::vector<int> rows(static_cast<std::size_t>(n), 0);
  visit_rod_shapes(robot, q, wrenches, rod_steps,
                   [&](int limb, double s, const RodState<double>& st) {
                     const auto i = static_cast<std::size_t>(limb);
                     shapes[i].row(rows[i]++) << s, st.x, st.y, st.theta;
                   });
  py::list out;
  for (const RowMatrix& shape : shapes) out.append(py::cast(shape));
  return out;
}

/// The Python view of a solution. Not usable (failed): NaN values, except FK's q, which echoes
/// `input_q` (the solver returns the last solved point of its path there).
template <class S>
Solution to_python(const RobotParams<double>& robot, const S& s, bool usable, bool shapes,
                   const JointVector* input_q = nullptr) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Solution out;
  out.num_limbs = robot.num_limbs;
  out.summary = s.summary;
  out.q = usable ? s.q : JointVector::Constant(robot.num_limbs, nan);
  if (input_q != nullptr) out.q = *input_q;
  out.pose = usable ? s.pose : Pose2<double>{nan, nan, nan};
  out.wrenches = s.wrenches;
  for (int i = 0; i < robot.num_limbs && !usable; ++i)
    out.wrenches[i] = Wrench<double>{nan, nan, nan};
  if (!usable) out.summary.max_strain = nan;
  if (usable && shapes) out.shapes = rod_shapes(robot, s.q, s.wrenches, s.summary.rod_steps);
  out.jacobian = s.jacobian;
  out.inverse = std::is_same_v<S, InverseSolution>;
  return out;
}

InverseSolution as_inverse(const Solution& s) {
  InverseSolution out;
  out.q = s.q;
  out.pose = s.pose;
  out.wrenches = s.wrenches;
  out.summary = s.summary;
  if (s.inverse) out.jacobian = s.jacobian;
  return out;
}

BatchResult allocate_batch(py::ssize_t rows, int n, BatchBuffers& buffers) {
  BatchResult b;
  b.q = py::array_t<double>({rows, static_cast<py::ssize_t>(n)});
  b.pose = py::array_t<double>({rows, py::ssize_t{3}});
  b.wrenches = py::array_t<double>({rows, static_cast<py::ssize_t>(n), py::ssize_t{3}});
  buffers = BatchBuffers{b.q.mutable_data(), b.pose.mutable_data(), b.wrenches.mutable_data(),
                         b.allocate(rows)};
  return b;
}

py::object forward(const RobotDescription& robot, const py::object& q_in,
                   const std::optional<Solution>& warm_start, bool shapes, const py::object& force,
                   double moment, const std::optional<SolverOptions>& options_in, bool path) {
  const RobotParams<double>& params = robot.params;
  const int n = params.num_limbs;
  const auto q = input_array(q_in, n, "q", "m");
  const PlatformLoad<double> load = make_load(force, moment);
  const SolverOptions options = options_or_default(options_in);
  if (q.ndim() == 1) {
    JointVector joints(n);
    for (int i = 0; i < n; ++i) joints(i) = q.at(i);
    std::unique_ptr<ForwardSolution> warm;
    if (warm_start) warm = std::make_unique<ForwardSolution>(as_forward(*warm_start));
    ForwardSolution s;
    {
      py::gil_scoped_release release;
      s = forward_kinematics_or_cold(params, joints, warm.get(), options, load);
    }
    return py::cast(to_python(params, s, is_equilibrium(s.summary), shapes, &joints));
  }
  if (warm_start) throw std::invalid_argument("warm_start: only for a single configuration");
  const py::ssize_t rows = q.shape(0);
  BatchBuffers buffers{};
  BatchResult batch = allocate_batch(rows, n, buffers);
  std::vector<ForwardSolution> solutions(shapes ? static_cast<std::size_t>(rows) : 0);
  {
    py::gil_scoped_release release;
    forward_batch(params, q.data(), rows, options, load, sequence_mode(path), buffers,
                  shapes ? solutions.data() : nullptr);
  }
  batch.name_statuses();
  if (shapes) {
    py::list all;
    for (const ForwardSolution& s : solutions) {
      all.append(is_equilibrium(s.summary)
                     ? py::object(rod_shapes(params, s.q, s.wrenches, s.summary.rod_steps))
                     : py::object(py::none()));
    }
    batch.shapes = all;
  }
  return py::cast(std::move(batch));
}

py::object inverse(const RobotDescription& robot, const py::object& pose_in,
                   const std::optional<Solution>& warm_start, bool shapes, const py::object& force,
                   double moment, const std::optional<SolverOptions>& options_in, bool path) {
  const RobotParams<double>& params = robot.params;
  const int n = params.num_limbs;
  if (n > 3) {
    throw std::invalid_argument("inverse: robots with more than 3 limbs are not supported (got " +
                                std::to_string(n) + " limbs)");
  }
  const PlatformLoad<double> load = make_load(force, moment);
  const SolverOptions options = options_or_default(options_in);
  py::object pose_like = pose_in;
  if (py::isinstance<Pose2<double>>(pose_in)) {
    const Pose2<double> p = pose_in.cast<Pose2<double>>();
    pose_like = py::cast(Eigen::Vector3d(p.x, p.y, p.theta));
  }
  const auto poses = input_array(pose_like, 3, "pose", "x m, y m, theta rad");
  if (poses.ndim() == 1) {
    const Pose2<double> pose{poses.at(0), poses.at(1), poses.at(2)};
    std::unique_ptr<InverseSolution> warm;
    if (warm_start) warm = std::make_unique<InverseSolution>(as_inverse(*warm_start));
    InverseSolution s;
    {
      py::gil_scoped_release release;
      s = inverse_kinematics_or_cold(params, pose, warm.get(), options, load);
    }
    return py::cast(to_python(params, s, is_equilibrium(s.summary), shapes));
  }
  if (warm_start) throw std::invalid_argument("warm_start: only for a single pose");
  const py::ssize_t rows = poses.shape(0);
  BatchBuffers buffers{};
  BatchResult batch = allocate_batch(rows, n, buffers);
  std::vector<InverseSolution> solutions(shapes ? static_cast<std::size_t>(rows) : 0);
  {
    py::gil_scoped_release release;
    inverse_batch(params, poses.data(), rows, options, load, sequence_mode(path), buffers,
                  shapes ? solutions.data() : nullptr);
  }
  batch.name_statuses();
  if (shapes) {
    py::list all;
    for (const InverseSolution& s : solutions) {
      all.append(is_equilibrium(s.summary)
                     ? py::object(rod_shapes(params, s.q, s.wrenches, s.summary.rod_steps))
                     : py::object(py::none()));
    }
    batch.shapes = all;
  }
  return py::cast(std::move(batch));
}

/// pcr.SolveStatus.
void bind_solve_status(py::module_& m) {
  py::enum_<SolveStatus>(m, "SolveStatus", "Outcome of a kinematics solve.")
      .value("converged", SolveStatus::kConverged)
      .value("max_iterations", SolveStatus::kMaxIterations)
      .value("singular", SolveStatus::kSingular)
      .value("bifurcation", SolveStatus::kBifurcation)
      .value("non_finite", SolveStatus::kNonFinite)
      .value("out_of_range", SolveStatus::kOutOfRange)
      .value("unstable", SolveStatus::kUnstable)
      .value("inaccurate", SolveStatus::kInaccurate)
      .value("unsupported", SolveStatus::kUnsupported)
      .value("invalid_input", SolveStatus::kInvalidInput);
}

/// pcr.SolverOptions: the Newton shooting settings.
void bind_solver_options(py::module_& m) {
  auto solver_options =
      py::class_<SolverOptions>(m, "SolverOptions",
                                "Newton shooting settings (pcr/kinematics.hpp).")
          .def(py::init<>())
          .def_readwrite("rod_steps", &SolverOptions::rod_steps,
                         "RK4 steps per rod; 0 chooses them from the solution's estimated error")
          .def_readwrite("position_accuracy", &SolverOptions::position_accuracy,
                         "target of the estimated error of solved lengths when rod_steps = 0 (m)")
          .def_readwrite("angle_accuracy", &SolverOptions::angle_accuracy,
                         "target of the estimated error of solved angles when rod_steps = 0 (rad)")
          .def_readwrite("min_rod_steps", &SolverOptions::min_rod_steps,
                         "least RK4 steps per rod when rod_steps = 0")
          .def_readwrite("max_rod_steps", &SolverOptions::max_rod_steps,
                         "most RK4 steps per rod when rod_steps = 0")
          .def_readwrite("max_iterations", &SolverOptions::max_iterations,
                         "Newton iterations per solve")
          .def_readwrite("tolerance", &SolverOptions::tolerance,
                         "max-norm of the scaled residual (lengths / l, forces / (EI / l^2))")
          .def_readwrite("chord_output_share", &SolverOptions::chord_output_share,
                         "share of the accuracy targets a chord run may leave on the outputs; 0 "
                         "runs every solve to the tolerance")
          .def_readwrite("max_line_search", &SolverOptions::max_line_search,
                         "step halvings of Newton's backtracking line search")
          .def_readwrite("continuation", &SolverOptions::continuation,
                         "when a direct solve fails, step the input from the last solution in "
                         "smaller increments")
          .def_readwrite("max_continuation_steps", &SolverOptions::max_continuation_steps,
                         "sub-solves a continuation may use in total")
          .def_readwrite("max_continuation_iterations", &SolverOptions::max_continuation_iterations,
                         "Newton iterations per sub-solve of a continuation")
          .def_readwrite("min_continuation_step", &SolverOptions::min_continuation_step,
                         "smallest continuation increment, a fraction of the whole path")
          .def_readwrite(
              "check_stability", &SolverOptions::check_stability,
              "check the elastic stability of every converged solution (at half its RK4 steps: "
              "about one residual-plus-Jacobian evaluation)")
          .def_readwrite(
              "stable_inverse", &SolverOptions::stable_inverse,
              "when IK converges on an unstable equilibrium, look for a stable one at the "
              "same pose (status 'unstable' when none is found)")
          .def_readwrite(
              "through_folds", &SolverOptions::through_folds,
              "a sequence whose warm solve stops at a fold follows the curve of solutions "
              "through it by pseudo-arclength continuation before the cold retry")
          .def_readwrite("max_arclength_steps", &SolverOptions::max_arclength_steps,
                         "points a pseudo-arclength trace may solve");
  def_value_semantics(solver_options);
}

/// pcr.Solution: one solved configuration.
void bind_solution(py::module_& m) {
  auto solution = py::class_<Solution>(
      m, "Solution",
      "One solved configuration. When the solve failed (converged is False; for IK also "
      "out_of_range is a valid equilibrium) q/pose/wrenches are NaN.");
  def_summary_properties(solution);
  def_solution_copies(solution);
  solution
      .def_property_readonly(
          "q", [](const Solution& s) -> Eigen::VectorXd { return s.q; }, "joint values (m)")
      .def_property_readonly(
          "pose", [](const Solution& s) { return s.pose; }, "platform pose ^W T_P (m, m, rad)")
      .def_property_readonly(
          "wrenches",
          [](const Solution& s) {
            RowMatrix w(s.num_limbs, 3);
            for (int i = 0; i < s.num_limbs; ++i)
              w.row(i) << s.wrenches[i].nx, s.wrenches[i].ny, s.wrenches[i].m;
            return w;
          },
          "(n, 3) proximal wrench of each rod: nx, ny (N), m (N m)")
      .def_readonly("shapes", &Solution::shapes,
                    "None, or (with shapes=True) one (steps + 1, 4) array per rod: s, x, y (m), "
                    "theta (rad) along the rod, in W")
      .def("__repr__",
           [](const Solution& s) {
             return "<pcr.Solution " + std::string(to_string(s.summary.status)) + ", " +
                    std::to_string(s.summary.iterations) + " iterations>";
           })
      // The solver's factorised Jacobian is not pickled: a warm start from an unpickled solution
      // evaluates its own first.
      .def(py::pickle(
          [](const Solution& s) {
            SolverSummary summary = s.summary;
            RowMatrix wrenches(s.num_limbs, 3);
            for (int i = 0; i < s.num_limbs; ++i)
              wrenches.row(i) << s.wrenches[i].nx, s.wrenches[i].ny, s.wrenches[i].m;
            return py::make_tuple(s.num_limbs, Eigen::VectorXd(s.q), s.pose, wrenches,
                                  fields_to_tuple(summary_fields(summary)), s.shapes, s.inverse);
          },
          [](const py::tuple& state) {
            if (state.size() != 7) throw py::value_error("Solution: not a pickled Solution");
            Solution s;
            s.num_limbs = state[0].cast<int>();
            if (s.num_limbs < 1 || s.num_limbs > kMaxLimbs)
              throw py::value_error("Solution: not a pickled Solution");
            s.q = state[1].cast<Eigen::VectorXd>();
            s.pose = state[2].cast<Pose2<double>>();
            const RowMatrix wrenches = state[3].cast<RowMatrix>();
            if (s.q.size() != s.num_limbs || wrenches.rows() != s.num_limbs || wrenches.cols() != 3)
              throw py::value_error("Solution: not a pickled Solution");
            for (int i = 0; i < s.num_limbs; ++i)
              s.wrenches[i] = Wrench<double>{wrenches(i, 0), wrenches(i, 1), wrenches(i, 2)};
            fields_from_tuple(summary_fields(s.summary), state[4].cast<py::tuple>(),
                              "Solution.summary");
            s.shapes = state[5];
            s.inverse = state[6].cast<bool>();
            return s;
          }));
}

/// pcr.BatchResult: the arrays of a batch.
void bind_batch_result(py::module_& m) {
  auto batch = py::class_<BatchResult>(
      m, "BatchResult",
      "Results of a batch, one row per input row. Rows that failed have NaN values (FK keeps its "
      "input q, IK its input pose).");
  def_summary_arrays(batch, "BatchResult",
                     "None, or a list (one per row) of None or per-rod (steps + 1, 4) arrays");
  batch.def_readonly("q", &BatchResult::q, "(N, n) joint values (m)")
      .def_readonly("pose", &BatchResult::pose, "(N, 3) platform poses x, y (m), theta (rad)")
      .def_readonly("wrenches", &BatchResult::wrenches, "(N, n, 3) proximal wrenches (N, N, N m)")
      // Pickling (and with it copy.copy and copy.deepcopy): the arrays, field by field.
      .def(py::pickle([](BatchResult b) { return fields_to_tuple(b.fields()); },
                      [](const py::tuple& state) {
                        BatchResult b;
                        fields_from_tuple(b.fields(), state, "BatchResult");
                        return b;
                      }));
}

/// Robot.forward, inverse, home and with_home_at, added to the class wrap_robot registered.
void bind_robot_kinematics(py::module_& m) {
  auto robot = py::reinterpret_borrow<py::class_<RobotDescription>>(m.attr("Robot"));
  robot
      .def("forward", &forward, py::arg("q"), py::kw_only(), py::arg("warm_start") = py::none(),
           py::arg("shapes") = false, py::arg("force") = no_force(), py::arg("moment") = 0.0,
           py::arg("options") = py::none(), py::arg("path") = false,
           "Forward kinematics. q: n joint values (m) -> Solution; or an (N, n) array -> "
           "BatchResult, as `pcr fk` solves rows: each on its own, in any order, on the branch "
           "connected to home; with path=True, a path the robot follows in this order, each row "
           "continued from the previous converged one (a failed one retried from home; through "
           "folds with options.through_folds). Joints outside q_range give status out_of_range "
           "(converged False, the pose of that equilibrium given). force (fx, fy) in N and moment "
           "in N m act on the platform at P's origin, in W. Releases the GIL.")
      .def("inverse", &inverse, py::arg("pose"), py::kw_only(), py::arg("warm_start") = py::none(),
           py::arg("shapes") = false, py::arg("force") = no_force(), py::arg("moment") = 0.0,
           py::arg("options") = py::none(), py::arg("path") = false,
           "Inverse kinematics. pose: a Pose or (x m, y m, theta rad) -> Solution; or an (N, 3) "
           "array -> BatchResult, rows as in forward (path: each continued from the previous), "
           "like `pcr ik`. Joints outside "
           "q_range give status out_of_range (converged False, q kept). With 2 limbs theta is "
           "solved for. Releases the GIL.")
      .def(
          "home",
          [](const RobotDescription& r, bool shapes, const py::object& force, double moment,
             const std::optional<SolverOptions>& options) {
            const PlatformLoad<double> load = make_load(force, moment);
            ForwardSolution s;
            {
              py::gil_scoped_release release;
              s = home_solution(r.params, options_or_default(options), load);
            }
            return to_python(r.params, s, s.summary.converged(), shapes);
          },
          py::kw_only(), py::arg("shapes") = false, py::arg("force") = no_force(),
          py::arg("moment") = 0.0, py::arg("options") = py::none(), "The home solution q = 0 (m).")
      .def(
          "with_home_at",
          [](const RobotDescription& r, const Pose2<double>& pose, const py::object& force,
             double moment, const std::optional<SolverOptions>& options) {
            const PlatformLoad<double> load = make_load(force, moment);
            RobotDescription out = r;
            bool found;
            {
              py::gil_scoped_release release;
              found = choose_home(r.params, pose, out.params, options_or_default(options), load);
            }
            if (!found) throw py::value_error("with_home_at: no home of the robot solves");
            return out;
          },
          py::arg("pose"), py::kw_only(), py::arg("force") = no_force(), py::arg("moment") = 0.0,
          py::arg("options") = py::none(),
          "A copy saying which of its homes the robot is in (each limb's home_bow), from its "
          "measured home pose ^W T_P (a Pose, m and rad): of the homes of every pattern of bow "
          "sides, the one nearest (a pre-stressed robot, n >= 4, has several; n <= 3: a copy). "
          "ValueError when no home solves. Releases the GIL.");
}

}  // namespace

ForwardSolution as_forward(const Solution& s) {
  ForwardSolution out;
  out.q = s.q;
  out.pose = s.pose;
  out.wrenches = s.wrenches;
  out.summary = s.summary;
  if (!s.inverse) out.jacobian = s.jacobian;
  return out;
}

void wrap_kinematics(py::module_& m) {
  bind_solve_status(m);
  bind_solver_options(m);
  bind_solution(m);
  bind_batch_result(m);
  bind_robot_kinematics(m);
}

}  // namespace pcr::python
