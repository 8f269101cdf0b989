// Trajectories and their ISO 9283 accuracy (pcr/trajectory.hpp, pcr/calib/accuracy.hpp): paths as
// (N, 3) arrays of poses (x m, y m, theta rad), attained poses as (N, R, 3) arrays (or a list of
// (R_k, 3) arrays when the pose counts differ), results as objects whose attributes are arrays.
#include <optional>

#include "calibration_bindings.hpp"
#include "pcr/calib/accuracy.hpp"

namespace pcr::python {
namespace {

/// (N, 3) array-like (or one (3,) pose) -> poses. ValueError naming `what` otherwise.
std::vector<Pose2<double>> pose_rows(const py::handle& object, const char* what) {
  const InputArray a = as_input_array(object);
  if (!a || a.ndim() < 1 || a.ndim() > 2 || a.shape(a.ndim() - 1) != 3) {
    throw std::invalid_argument(std::string(what) +
                                ": expected an (N, 3) array of poses (x m, y m, theta rad), got " +
                                describe_value(object));
  }
  const py::ssize_t rows = a.ndim() == 1 ? 1 : a.shape(0);
  std::vector<Pose2<double>> out(static_cast<std::size_t>(rows));
  const double* p = a.data();
  for (py::ssize_t r = 0; r < rows; ++r)
    out[r] = Pose2<double>{p[3 * r], p[3 * r + 1], p[3 * r + 2]};
  return out;
}

/// (N, R, 3) array or a sequence of N (R_k, 3) arrays -> attained[pose][cycle].
std::vector<std::vector<Pose2<double>>> attained_rows(const py::handle& object) {
  std::vector<std::vector<Pose2<double>>> out;
  if (py::isinstance<py::array>(object) && object.cast<py::array>().ndim() == 3) {
    const InputArray a = InputArray::ensure(object);
    if (!a || a.shape(2) != 3) {
      throw std::invalid_argument("attained: expected an (N, R, 3) array of poses, got " +
                                  describe_value(object));
    }
    const double* p = a.data();
    out.resize(static_cast<std::size_t>(a.shape(0)));
    for (py::ssize_t k = 0; k < a.shape(0); ++k) {
      for (py::ssize_t j = 0; j < a.shape(1); ++j) {
        const double* v = p + 3 * (k * a.shape(1) + j);
        out[k].push_back(Pose2<double>{v[0], v[1], v[2]});
      }
    }
    return out;
  }
  if (!py::isinstance<py::sequence>(object) || py::isinstance<py::str>(object)) {
    throw std::invalid_argument(
        "attained: expected an (N, R, 3) array or a list of N (R_k, 3) "
        "arrays of poses");
  }
  for (const py::handle& item : object.cast<py::sequence>()) {
    const std::string what = "attained[" + std::to_string(out.size()) + "]";
    out.push_back(pose_rows(item, what.c_str()));
  }
  return out;
}

/// attained[pose][cycle] -> (N, R, 3) when every pose has R cycles, else a list of (R_k, 3).
py::object attained_array(const std::vector<std::vector<Pose2<double>>>& attained) {
  bool uniform = true;
  for (const auto& a : attained) uniform = uniform && a.size() == attained.front().size();
  if (!uniform || attained.empty()) {
    py::list out;
    for (const auto& a : attained) out.append(poses_matrix(a));
    return std::move(out);
  }
  const py::ssize_t n = static_cast<py::ssize_t>(attained.size());
  const py::ssize_t r = static_cast<py::ssize_t>(attained.front().size());
  py::array_t<double> out({n, r, py::ssize_t{3}});
  double* p = out.mutable_data();
  for (const auto& a : attained) {
    for (const Pose2<double>& v : a) {
      *p++ = v.x;
      *p++ = v.y;
      *p++ = v.theta;
    }
  }
  return std::move(out);
}

template <class F>
Eigen::VectorXd column(const Iso9283Result& r, F value) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(r.poses.size()));
  for (std::size_t k = 0; k < r.poses.size(); ++k)
    out(static_cast<Eigen::Index>(k)) = value(r.poses[k]);
  return out;
}

template <class F>
std::vector<Pose2<double>> column_poses(const Iso9283Result& r, F value) {
  std::vector<Pose2<double>> out;
  for (const Iso9283Pose& p : r.poses) out.push_back(value(p));
  return out;
}

py::dict stats_dict(const Iso9283Stats& s) {
  py::dict d;
  d["max"] = s.max;
  d["mean"] = s.mean;
  d["min"] = s.min;
  return d;
}

AttainedFrame attained_frame(const std::string& name) {
  if (name == "model") return AttainedFrame::kModelExtrinsics;
  if (name == "true") return AttainedFrame::kTrueExtrinsics;
  throw std::invalid_argument("frame: expected 'model' or 'true', got '" + name + "'");
}

PathCommandOptions command_options(double strain_limit, const py::object& force, double moment,
                                   const std::optional<SolverOptions>& solver,
                                   bool cold_start_fallback) {
  PathCommandOptions o;
  o.step.strain_limit = strain_limit;
  o.step.load = make_load(force, moment);
  o.step.solver = options_or_default(solver);
  o.step.cold_start_fallback = cold_start_fallback;
  return checked_options(o);
}

py::dict command_dict(const PathCommand& c, int n) {
  RowMatrix q(static_cast<Eigen::Index>(c.q.size()), n);
  for (std::size_t r = 0; r < c.q.size(); ++r)
    q.row(static_cast<Eigen::Index>(r)) = c.q[r].transpose();
  py::dict d;
  d["q"] = q;
  d["poses"] = poses_matrix(c.poses);
  d["max_strain"] = Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(
      c.max_strain.data(), static_cast<Eigen::Index>(c.max_strain.size())));
  d["iterations"] =
      py::array_t<int>(static_cast<py::ssize_t>(c.iterations.size()), c.iterations.data());
  return d;
}

std::vector<std::pair<std::string, const Iso9283Result*>> named_rows(const py::handle& rows) {
  std::vector<std::pair<std::string, const Iso9283Result*>> out;
  if (py::isinstance<Iso9283Result>(rows)) {
    out.emplace_back("result", rows.cast<const Iso9283Result*>());
    return out;
  }
  if (py::isinstance<py::dict>(rows)) {
    for (const auto& kv : rows.cast<py::dict>()) {
      out.emplace_back(py::str(kv.first).cast<std::string>(),
                       kv.second.cast<const Iso9283Result*>());
    }
    return out;
  }
  for (const py::handle& item : rows.cast<py::sequence>()) {
    const py::tuple t = item.cast<py::tuple>();
    if (t.size() != 2) throw std::invalid_argument("rows: expected (name, Iso9283Result) pairs");
    out.emplace_back(t[0].cast<std::string>(), t[1].cast<const Iso9283Result*>());
  }
  return out;
}

/// The paper's square and circle paths, and paths from CSV.
void bind_paths(py::module_& m) {
  m.attr("PAPER_SQUARE_SIDE") = kPaperSquareSide;
  m.attr("PAPER_CIRCLE_DIAMETER") = kPaperCircleDiameter;

  m.def(
      "square_path",
      [](double side, const py::object& centre, double rotation, double theta, int count) {
        SquarePath s;
        s.side = side;
        s.centre = to_vector<2>(centre, "centre", "x, y in m");
        s.rotation = checked_number(rotation, "rotation", "rad");
        s.theta = theta;
        s.num_poses = count;
        return poses_matrix(square_path(checked_options(s)));
      },
      py::arg("side") = kPaperSquareSide, py::kw_only(),
      py::arg("centre") = py::make_tuple(0.0, 0.0), py::arg("rotation") = 0.0,
      py::arg("theta") = 0.0, py::arg("count") = 40,
      "The paper's square (side m) as a (count, 3) array of poses, counter-clockwise from the "
      "corner (-side/2, -side/2) before `rotation` (rad), at the constant orientation theta; "
      "closed (the first pose is not repeated), corners included when count is a multiple of 4.");
  m.def(
      "circle_path",
      [](double diameter, const py::object& centre, double start_angle, double theta, int count) {
        CirclePath c;
        c.diameter = diameter;
        c.centre = to_vector<2>(centre, "centre", "x, y in m");
        c.start_angle = checked_number(start_angle, "start_angle", "rad");
        c.theta = theta;
        c.num_poses = count;
        return poses_matrix(circle_path(checked_options(c)));
      },
      py::arg("diameter") = kPaperCircleDiameter, py::kw_only(),
      py::arg("centre") = py::make_tuple(0.0, 0.0), py::arg("start_angle") = 0.0,
      py::arg("theta") = 0.0, py::arg("count") = 36,
      "The paper's circle (diameter m) as a (count, 3) array of poses, counter-clockwise from "
      "the polar angle start_angle (rad), at the constant orientation theta.");
  m.def(
      "load_path_csv",
      [](const std::filesystem::path& path) {
        return poses_matrix(load_path_csv(input_path(path)));
      },
      py::arg("path"),
      "A path from CSV (columns x,y,theta in m, m, rad) -> (N, 3). FileNotFoundError when it "
      "does not exist, ValueError naming the file and line.");
}

/// command_path: IK along a path.
void bind_command_path(py::module_& m) {
  m.def(
      "command_path",
      [](const RobotDescription& model, const py::object& path, double strain_limit,
         const py::object& force, double moment, const std::optional<SolverOptions>& solver,
         bool cold_start_fallback) {
        const std::vector<Pose2<double>> poses = pose_rows(path, "path");
        const PathCommandOptions o =
            command_options(strain_limit, force, moment, solver, cold_start_fallback);
        PathCommand c;
        {
          py::gil_scoped_release release;
          c = command_path(model.params, poses, o);
        }
        return command_dict(c, model.params.num_limbs);
      },
      py::arg("robot"), py::arg("path"), py::kw_only(),
      py::arg("strain_limit") = kDefaultStrainLimit, py::arg("force") = no_force(),
      py::arg("moment") = 0.0, py::arg("options") = py::none(),
      py::arg("cold_start_fallback") = true,
      "IK along a path ((N, 3) poses), warm-started pose to pose from home. Returns a dict: q "
      "(N, n) m, poses (N, 3) (theta solved when n = 2), max_strain (N,), iterations (N,). "
      "ValueError 'pose k (x, y, theta): reason' at the first pose out of the workspace, the "
      "strokes or the strain limit. Releases the GIL.");
}

/// pcr.Iso9283Result: per-pose arrays and the Table 4 summary.
void bind_iso9283_result(py::module_& m) {
  py::class_<Iso9283Result>(m, "Iso9283Result",
                            "ISO 9283 pose accuracy and repeatability of a path: per-pose arrays "
                            "(N,) or (N, 3) and the Table 4 summary (SI units).")
      .def_property_readonly(
          "commanded",
          [](const Iso9283Result& r) {
            return poses_matrix(column_poses(r, [](const Iso9283Pose& p) { return p.commanded; }));
          },
          "(N, 3) commanded poses")
      .def_property_readonly(
          "barycentre",
          [](const Iso9283Result& r) {
            return poses_matrix(column_poses(r, [](const Iso9283Pose& p) { return p.barycentre; }));
          },
          "(N, 3) mean attained poses (x_bar, y_bar, theta_bar)")
      .def_property_readonly(
          "cycles",
          [](const Iso9283Result& r) {
            py::array_t<int> out(static_cast<py::ssize_t>(r.poses.size()));
            for (std::size_t k = 0; k < r.poses.size(); ++k) out.mutable_at(k) = r.poses[k].cycles;
            return out;
          },
          "(N,) attained poses per commanded pose")
      .def_property_readonly(
          "ap_x",
          [](const Iso9283Result& r) {
            return column(r, [](const Iso9283Pose& p) { return p.ap_x; });
          },
          "(N,) x_bar - x_c (m)")
      .def_property_readonly(
          "ap_y",
          [](const Iso9283Result& r) {
            return column(r, [](const Iso9283Pose& p) { return p.ap_y; });
          },
          "(N,) y_bar - y_c (m)")
      .def_property_readonly(
          "ap_p",
          [](const Iso9283Result& r) {
            return column(r, [](const Iso9283Pose& p) { return p.ap_p; });
          },
          "(N,) AP_p, Eq. 10 (m)")
      .def_property_readonly(
          "ap_theta",
          [](const Iso9283Result& r) {
            return column(r, [](const Iso9283Pose& p) { return p.ap_theta; });
          },
          "(N,) AP_theta, Eq. 11, signed (rad)")
      .def_property_readonly(
          "l_bar",
          [](const Iso9283Result& r) {
            return column(r, [](const Iso9283Pose& p) { return p.l_bar; });
          },
          "(N,) mean distance to the barycentre (m)")
      .def_property_readonly(
          "s_l",
          [](const Iso9283Result& r) {
            return column(r, [](const Iso9283Pose& p) { return p.s_l; });
          },
          "(N,) its sample standard deviation (m)")
      .def_property_readonly(
          "rp_l",
          [](const Iso9283Result& r) {
            return column(r, [](const Iso9283Pose& p) { return p.rp_l; });
          },
          "(N,) RP_l = l_bar + 3 S_l (m)")
      .def_property_readonly(
          "s_theta",
          [](const Iso9283Result& r) {
            return column(r, [](const Iso9283Pose& p) { return p.s_theta; });
          },
          "(N,) sample std of theta (rad)")
      .def_property_readonly(
          "rp_theta",
          [](const Iso9283Result& r) {
            return column(r, [](const Iso9283Pose& p) { return p.rp_theta; });
          },
          "(N,) 3 S_theta: RP_theta is +-rp_theta (rad)")
      .def_property_readonly(
          "summary",
          [](const Iso9283Result& r) {
            py::dict d;
            d["ap_p"] = stats_dict(r.ap_p);
            d["ap_theta_abs"] = stats_dict(r.ap_theta_abs);
            d["rp_l"] = stats_dict(r.rp_l);
            d["rp_theta"] = stats_dict(r.rp_theta);
            return d;
          },
          "Table 4: {'ap_p', 'ap_theta_abs', 'rp_l', 'rp_theta'} -> {'max', 'mean', 'min'} (m, "
          "rad)")
      .def("poses_csv", &iso9283_poses_csv,
           "Per-pose statistics as CSV (pose,x_c,y_c,theta_c,x_bar,...,rp_theta; SI units).")
      .def(
          "to_json",
          [](const Iso9283Result& r, const std::string& name) {
            return iso9283_json({{name, &r}});
          },
          py::arg("name") = "result", "Summary and per-pose statistics as JSON (SI units).")
      .def("__len__", [](const Iso9283Result& r) { return r.poses.size(); })
      .def("__repr__", [](const Iso9283Result& r) {
        return "Iso9283Result(" + std::to_string(r.poses.size()) + " poses, AP_p max " +
               std::to_string(r.ap_p.max * 1e6) + " um, mean " + std::to_string(r.ap_p.mean * 1e6) +
               " um)";
      });
}

/// iso9283, iso9283_table, iso9283_json: the statistics and Table 4.
void bind_iso9283(py::module_& m) {
  m.def(
      "iso9283",
      [](const py::object& commanded, const py::object& attained) {
        const std::vector<Pose2<double>> c = pose_rows(commanded, "commanded");
        const std::vector<std::vector<Pose2<double>>> a = attained_rows(attained);
        return iso9283(c, a);
      },
      py::arg("commanded"), py::arg("attained"),
      "ISO 9283 statistics: commanded (N, 3) poses, attained (N, R, 3) (or a list of N "
      "(R_k, 3) arrays, R_k >= 2) in the same frame -> Iso9283Result. ValueError on mismatched "
      "sizes, fewer than 2 attained poses or NaN.");
  m.def(
      "iso9283_table",
      [](const py::object& rows) { return iso9283_table_markdown(named_rows(rows)); },
      py::arg("rows"),
      "Table 4 (AP_p um, |AP_theta| mrad: max, mean, min; RP) as Markdown, one row per "
      "result: a dict {name: Iso9283Result}, a list of (name, result) pairs, or one result.");
  m.def(
      "iso9283_json", [](const py::object& rows) { return iso9283_json(named_rows(rows)); },
      py::arg("rows"), "Like iso9283_table, as JSON (SI units).");
}

/// pcr.AccuracyEvaluation and evaluate_on_virtual_robot.
void bind_accuracy_evaluation(py::module_& m) {
  py::class_<AccuracyEvaluation>(m, "AccuracyEvaluation",
                                 "A path commanded by a model and run on a virtual robot.")
      .def_property_readonly(
          "commanded", [](const AccuracyEvaluation& e) { return poses_matrix(e.commanded); },
          "(N, 3) commanded poses (m, m, rad)")
      .def_property_readonly(
          "q",
          [](const AccuracyEvaluation& e) -> py::object {
            const py::dict d = command_dict(
                e.command, e.command.q.empty() ? 0 : static_cast<int>(e.command.q[0].size()));
            return d["q"];  // a py::object owning the array, not an accessor into the temporary
                            // dict
          },
          "(N, n) commanded joints (m)")
      .def_property_readonly(
          "command",
          [](const AccuracyEvaluation& e) {
            return command_dict(e.command,
                                e.command.q.empty() ? 0 : static_cast<int>(e.command.q[0].size()));
          },
          "dict as returned by command_path")
      .def_property_readonly(
          "attained", [](const AccuracyEvaluation& e) { return attained_array(e.attained); },
          "(N, R, 3) attained platform poses ^W T_P, [pose, cycle]")
      .def_property_readonly(
          "iso", [](const AccuracyEvaluation& e) { return e.iso; }, "the Iso9283Result (a copy)")
      .def("__len__", [](const AccuracyEvaluation& e) { return e.commanded.size(); });

  m.def(
      "evaluate_on_virtual_robot",
      [](const RobotDescription& model, VirtualRobot& robot, const py::object& path, int repeat,
         const std::string& frame, double strain_limit, const py::object& force, double moment,
         const std::optional<SolverOptions>& solver) {
        AccuracyOptions o;
        o.repeat = repeat;
        o.frame = attained_frame(frame);
        o.command = command_options(strain_limit, force, moment, solver, true);
        checked_options(o);
        const std::vector<Pose2<double>> poses = pose_rows(path, "path");
        py::gil_scoped_release release;
        return evaluate_on_virtual_robot(model.params, robot, poses, o);
      },
      py::arg("model"), py::arg("robot"), py::arg("path"), py::kw_only(), py::arg("repeat") = 30,
      py::arg("frame") = "model", py::arg("strain_limit") = kDefaultStrainLimit,
      py::arg("force") = no_force(), py::arg("moment") = 0.0, py::arg("options") = py::none(),
      "Commands `path` ((N, 3) poses) with `model` (a Robot, nominal or identified), then runs "
      "`repeat` cycles on the VirtualRobot `robot` (every cycle visits the poses in order). "
      "frame: 'model' maps the camera measurements to W with the model's extrinsics (the "
      "paper's way, gauge invariant), 'true' with the virtual robot's true ones. force/moment: "
      "a known load the model commands with (the virtual robot applies its own). Returns an "
      "AccuracyEvaluation (commanded, q, attained (N, R, 3), iso). Releases the GIL.");
}

/// load_measured_csv, measured_to_csv: measured poses as CSV.
void bind_measured_csv(py::module_& m) {
  m.def(
      "load_measured_csv",
      [](const std::filesystem::path& path) {
        const MeasuredPath mp = load_measured_csv(input_path(path));
        return py::make_tuple(poses_matrix(mp.commanded), attained_array(mp.attained));
      },
      py::arg("path"),
      "Measured poses CSV (pose,x_c,y_c,theta_c,x,y,theta) -> (commanded (N, 3), attained "
      "(N, R, 3), or a list of (R_k, 3) arrays when the counts differ). FileNotFoundError when "
      "it does not exist, ValueError naming the file and line.");
  m.def(
      "measured_to_csv",
      [](const py::object& commanded, const py::object& attained) {
        return measured_to_csv(pose_rows(commanded, "commanded"), attained_rows(attained));
      },
      py::arg("commanded"), py::arg("attained"),
      "The measured poses CSV text (the format load_measured_csv reads).");
}

}  // namespace

void wrap_accuracy(py::module_& m) {
  bind_paths(m);
  bind_command_path(m);
  bind_iso9283_result(m);
  bind_iso9283(m);
  bind_accuracy_evaluation(m);
  bind_measured_csv(m);
}

}  // namespace pcr::python
