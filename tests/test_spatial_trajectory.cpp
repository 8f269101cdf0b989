// Spatial paths (pcr/spatial/trajectory.hpp), IK along them and ISO 9283 in 3-D
// (pcr/calib/spatial_accuracy.hpp): the paths against their closed forms, the statistics against
// hand computations on attained poses built with known offsets and scatter (and Eigen's slerp for
// the mean orientation), and IK along a small circle on the reference robot against FK whose rods
// are integrated by CVODE.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "pcr/calib/spatial_accuracy.hpp"
#include "pcr/input_error.hpp"
#include "spatial_test_support.hpp"

namespace pcr {
namespace {

using namespace pcr::testing;  // spatial_test_support.hpp

Vector4d quaternion(const Eigen::Quaterniond& h) { return Vector4d(h.w(), h.x(), h.y(), h.z()); }

/// A random rotation (seeded): axis uniform on the sphere, angle up to pi.
Eigen::Quaterniond random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> angle(0.0, M_PI);
  return Eigen::Quaterniond(
      Eigen::AngleAxisd(angle(rng), Vector3d(g(rng), g(rng), g(rng)).normalized()));
}

/// The point of a path in its plane's frame (Eigen's rotation, not the path's).
Vector3d local(const Eigen::Quaterniond& plane, const Vector3d& centre, const Vector3d& p) {
  return plane.toRotationMatrix().transpose() * (p - centre);
}

/// The perimeter fraction of a point on the square's edges, counter-clockwise from the corner
/// (-s/2, -s/2), written out edge by edge.
double perimeter_fraction(double u, double v, double s) {
  const double h = s / 2, tol = 1e-12 * s;
  if (std::abs(v + h) <= tol && u < h - tol) return (u + h) / (4 * s);
  if (std::abs(u - h) <= tol && v < h - tol) return (s + v + h) / (4 * s);
  if (std::abs(v - h) <= tol && u > -h + tol) return (2 * s + h - u) / (4 * s);
  return (3 * s + h - v) / (4 * s);
}

/// How far the polar angle of a point in its plane's frame lies from `expected`, modulo 2 pi.
double polar_angle_gap(const Vector3d& l, double expected) {
  return std::abs(std::remainder(std::atan2(l.y(), l.x()) - expected, 2 * M_PI));
}

/// Distance between two fractions of a closed path, modulo 1.
double fraction_gap(double a, double b) {
  const double d = std::abs(a - b);
  return std::min(d, 1 - d);
}

// ---- Path geometry ------------------------------------------------------------------------------

TEST(SpatialTrajectory, SquarePosesLieOnTheEdgesAtTheirPerimeterFraction) {
  std::mt19937_64 rng(11);
  double worst_plane = 0, worst_edge = 0, worst_fraction = 0;
  for (int trial = 0; trial < 8; ++trial) {
    const Eigen::Quaterniond plane = random_rotation(rng), platform = random_rotation(rng);
    SpatialSquarePath square;
    square.centre = Vector3d(0.01 * trial, -0.02, 0.4);
    // Any scale: the frame's rotation is that of the unit quaternion.
    square.plane_orientation = (1 + trial) * quaternion(plane);
    square.orientation = quaternion(platform);
    square.side = 1e-3 * (1 + trial);
    square.start = 0.1 * trial;
    square.num_poses = 40 + 4 * trial;
    ASSERT_TRUE(square.is_valid());
    const double s = square.side;
    for (int k = 0; k < square.size(); ++k) {
      const SpatialPose<double> p = square.pose(k);
      const Vector3d l = local(plane, square.centre, p.position);
      worst_plane = std::max(worst_plane, std::abs(l.z()));
      // On the boundary of the square: the larger coordinate is half the side.
      worst_edge =
          std::max(worst_edge, std::abs(std::max(std::abs(l.x()), std::abs(l.y())) - s / 2));
      const double expected = std::fmod(square.start + static_cast<double>(k) / square.size(), 1.0);
      worst_fraction =
          std::max(worst_fraction, fraction_gap(perimeter_fraction(l.x(), l.y(), s), expected));
      EXPECT_EQ(p.orientation, square.orientation);
    }
    // Closed: the pose after the last is the first.
    EXPECT_LT((square.pose(square.size()).position - square.pose(0).position).norm(), 1e-15);
  }
  std::printf("square: off the plane %.1e m, off the edges %.1e m, perimeter fraction %.1e\n",
              worst_plane, worst_edge, worst_fraction);
  EXPECT_LT(worst_plane, 1e-15);
  EXPECT_LT(worst_edge, 1e-15);
  EXPECT_LT(worst_fraction, 1e-12);
  // The default square: side 2 mm, its corners are poses 0, 10, 20, 30.
  const SpatialSquarePath square;
  EXPECT_LT((square.pose(10).position - Vector3d(1e-3, -1e-3, 0)).norm(), 1e-18);
  EXPECT_LT((square.pose(20).position - Vector3d(1e-3, 1e-3, 0)).norm(), 1e-18);
}

TEST(SpatialTrajectory, CircleHasItsRadiusNormalAndPolarAngles) {
  std::mt19937_64 rng(12);
  double worst_radius = 0, worst_plane = 0, worst_angle = 0, worst_turn = 0;
  for (int trial = 0; trial < 8; ++trial) {
    const Eigen::Quaterniond plane = random_rotation(rng);
    SpatialCirclePath circle;
    circle.centre = Vector3d(-0.1, 0.05 * trial, 0.3);
    circle.plane_orientation = quaternion(plane);
    circle.orientation = quaternion(random_rotation(rng));
    circle.diameter = 2e-3 + 1e-3 * trial;
    circle.start = -3.0 + 0.8 * trial;
    circle.num_poses = 12 + trial;
    ASSERT_TRUE(circle.is_valid());
    const Vector3d normal = plane.toRotationMatrix().col(2);
    for (int k = 0; k < circle.size(); ++k) {
      const SpatialPose<double> p = circle.pose(k);
      const Vector3d l = local(plane, circle.centre, p.position);
      worst_radius = std::max(worst_radius, std::abs(l.head<2>().norm() - circle.diameter / 2));
      worst_plane = std::max(worst_plane, std::abs((p.position - circle.centre).dot(normal)));
      const double expected = circle.start + 2 * M_PI * k / circle.size();
      worst_angle = std::max(worst_angle, polar_angle_gap(l, expected));
      // Counter-clockwise about the normal: consecutive radii turn along +normal.
      const Vector3d r0 = p.position - circle.centre;
      const Vector3d r1 = circle.pose(k + 1).position - circle.centre;
      const double turn = std::atan2(r0.cross(r1).dot(normal), r0.dot(r1));
      worst_turn = std::max(worst_turn, std::abs(turn - 2 * M_PI / circle.size()));
    }
    EXPECT_LT((circle.pose(circle.size()).position - circle.pose(0).position).norm(), 1e-15);
  }
  std::printf("circle: radius %.1e m, off the plane %.1e m, polar angle %.1e rad, step %.1e rad\n",
              worst_radius, worst_plane, worst_angle, worst_turn);
  EXPECT_LT(worst_radius, 1e-15);
  EXPECT_LT(worst_plane, 1e-15);
  EXPECT_LT(worst_angle, 1e-12);
  EXPECT_LT(worst_turn, 1e-11);
}

TEST(SpatialTrajectory, HelixHasItsPitchRadiusAndEnds) {
  std::mt19937_64 rng(13);
  double worst_radius = 0, worst_axial = 0, worst_angle = 0, worst_pitch = 0;
  for (int trial = 0; trial < 6; ++trial) {
    const Eigen::Quaterniond axis = random_rotation(rng);
    SpatialHelixPath helix;
    helix.centre = Vector3d(0, 0.01, 0.4);
    helix.axis_orientation = quaternion(axis);
    helix.diameter = 3e-3;
    helix.pitch = trial % 2 == 0 ? 1e-3 * (1 + trial) : -5e-4;
    helix.turns = 1 + trial;
    helix.start = 0.5 * trial - 1;
    const int per_turn = 12 + 4 * trial;
    helix.num_poses = per_turn * (1 + trial) + 1;
    ASSERT_TRUE(helix.is_valid());
    const Vector3d e3 = axis.toRotationMatrix().col(2);
    for (int k = 0; k < helix.size(); ++k) {
      const Vector3d l = local(axis, helix.centre, helix.pose(k).position);
      const double f = static_cast<double>(k) / (helix.size() - 1);
      worst_radius = std::max(worst_radius, std::abs(l.head<2>().norm() - helix.diameter / 2));
      worst_axial = std::max(worst_axial, std::abs(l.z() - helix.pitch * helix.turns * (f - 0.5)));
      worst_angle =
          std::max(worst_angle, polar_angle_gap(l, helix.start + 2 * M_PI * helix.turns * f));
      // One turn on: the same point moved by the pitch along the axis.
      if (k + per_turn < helix.size()) {
        const Vector3d d = helix.pose(k + per_turn).position - helix.pose(k).position;
        worst_pitch = std::max(worst_pitch, (d - helix.pitch * e3).norm());
      }
    }
    // Not closed: the ends are the axis' ends, turns apart.
    const Vector3d ends = helix.pose(helix.size() - 1).position - helix.pose(0).position;
    EXPECT_LT((ends - helix.pitch * helix.turns * e3).norm(), 1e-15);
    // Beyond its ends the fraction is clamped.
    EXPECT_EQ(helix.at(1.5).position, helix.at(1).position);
  }
  std::printf("helix: radius %.1e m, axial %.1e m, polar angle %.1e rad, pitch %.1e m\n",
              worst_radius, worst_axial, worst_angle, worst_pitch);
  EXPECT_LT(worst_radius, 1e-15);
  EXPECT_LT(worst_axial, 1e-15);
  EXPECT_LT(worst_angle, 1e-11);
  EXPECT_LT(worst_pitch, 1e-15);
}

TEST(SpatialTrajectory, RangesNameTheField) {
  std::string error;
  SpatialSquarePath square;
  square.side = 0.2;
  EXPECT_FALSE(square.is_valid(&error, "square."));
  EXPECT_EQ(error, "square.side: expected a number from 1e-06 to 0.1 (m), got 0.2");
  square = SpatialSquarePath();
  square.centre.z() = 1.5;
  EXPECT_FALSE(square.is_valid(&error));
  EXPECT_EQ(error, "centre: expected a number from -1 to 1 (m), got 1.5");
  SpatialCirclePath circle;
  circle.plane_orientation.setZero();
  EXPECT_FALSE(circle.is_valid(&error));
  EXPECT_EQ(error, "|plane_orientation|: expected a number from 1e-06 to 1000000, got 0");
  circle = SpatialCirclePath();
  circle.orientation[2] = NAN;
  EXPECT_FALSE(circle.is_valid(&error));
  EXPECT_EQ(error.substr(0, 14), "|orientation|:");
  SpatialHelixPath helix;
  helix.turns = 0;
  EXPECT_FALSE(helix.is_valid(&error));
  EXPECT_EQ(error, "turns: expected a number from 0.001 to 1000, got 0");
  helix.turns = 1;
  helix.axis_orientation *= 1e-9;
  EXPECT_FALSE(helix.is_valid(&error));
  EXPECT_EQ(error, "|axis_orientation|: expected a number from 1e-06 to 1000000, got 1e-09");
  helix.axis_orientation = identity_quaternion<double>();
  helix.turns = 0;
  try {
    spatial_helix_path(helix);
    ADD_FAILURE() << "no exception";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "spatial_helix_path: turns: expected a number from 0.001 to 1000, got 0");
  }
  // The vectors hold the generators' poses.
  const std::vector<SpatialPose<double>> poses = spatial_circle_path();
  ASSERT_EQ(poses.size(), 36u);
  EXPECT_EQ(poses[7].position, SpatialCirclePath().pose(7).position);
  SpatialPose<double> buffer[5];
  EXPECT_EQ(fill_path(SpatialHelixPath(), buffer, 5), 5);
  EXPECT_EQ(buffer[4].position, SpatialHelixPath().pose(4).position);
}

// ---- ISO 9283 in 3-D ----------------------------------------------------------------------------

/// Attained poses about a barycentre (p_bar, R_bar): pairs p_bar +- s_i e_i, R_bar exp(+-eta_i e_i)
/// for i = x, y, z, each pair `repeat` times. The deviations' mean is zero, so (p_bar, R_bar) is
/// the barycentre; l_j = s_i, and the deviations about axis i are +-eta_i on a third of the poses.
std::vector<SpatialPose<double>> symmetric_scatter(const SpatialPose<double>& bar,
                                                   const Vector3d& s, const Vector3d& eta,
                                                   int repeat) {
  std::vector<SpatialPose<double>> out;
  const Eigen::Quaterniond r_bar = eigen_quaternion(bar.orientation);
  for (int r = 0; r < repeat; ++r) {
    for (int i = 0; i < 3; ++i) {
      for (double sign : {1.0, -1.0}) {
        SpatialPose<double> p;
        p.position = bar.position + sign * s[i] * Vector3d::Unit(i);
        p.orientation = quaternion(
            r_bar * Eigen::Quaterniond(Eigen::AngleAxisd(sign * eta[i], Vector3d::Unit(i))));
        out.push_back(p);
      }
    }
  }
  return out;
}

TEST(SpatialIso9283, KnownOffsetsAndScatterGiveTheHandComputedStatistics) {
  std::mt19937_64 rng(21);
  const Vector3d s(1e-6, 2e-6, 4e-6);    // m
  const Vector3d eta(2e-6, 5e-6, 7e-6);  // rad
  std::vector<SpatialPose<double>> commanded;
  std::vector<std::vector<SpatialPose<double>>> attained;
  std::vector<Vector3d> offsets, turns;
  for (int k = 0; k < 5; ++k) {
    SpatialPose<double> c;
    c.position = Vector3d(0.001 * k, -0.002, 0.4);
    c.orientation = quaternion(random_rotation(rng));
    // |(3, -4, 12)| = 13: AP_p of 13 (k + 1) um.
    const Vector3d d = 1e-6 * (k + 1) * Vector3d(3, -4, 12);
    const Vector3d delta = 1e-4 * Vector3d(1 + k, -2, 3 - k);  // in P_c
    SpatialPose<double> bar;
    bar.position = c.position + d;
    bar.orientation =
        quaternion(eigen_quaternion(c.orientation) *
                   Eigen::Quaterniond(Eigen::AngleAxisd(delta.norm(), delta.normalized())));
    commanded.push_back(c);
    attained.push_back(symmetric_scatter(bar, s, eta, 1 + k));
    offsets.push_back(d);
    turns.push_back(delta);
  }
  const SpatialIso9283Result result = iso9283_spatial(commanded, attained);
  ASSERT_EQ(result.poses.size(), commanded.size());
  double worst_ap = 0, worst_abc = 0, worst_rp_l = 0, worst_rp_abc = 0;
  for (std::size_t k = 0; k < commanded.size(); ++k) {
    const SpatialIso9283Pose& p = result.poses[k];
    const double n = static_cast<double>(attained[k].size());
    EXPECT_EQ(p.cycles, static_cast<int>(n));
    worst_ap = std::max(worst_ap, std::abs(p.ap_p - 13e-6 * (k + 1)));
    worst_ap = std::max(worst_ap, (p.ap_xyz - offsets[k]).norm());
    worst_abc = std::max(worst_abc, (p.ap_abc - turns[k]).norm());
    // l_j takes each s_i on n / 3 poses.
    const double l_bar = s.sum() / 3;
    const double s_l = std::sqrt(n / 3 * (s.array() - l_bar).square().sum() / (n - 1));
    worst_rp_l = std::max(worst_rp_l, std::abs(p.rp_l - (l_bar + 3 * s_l)) / s.maxCoeff());
    // The deviation about axis i is +-eta_i on n / 3 poses, 0 on the others.
    const Vector3d s_abc = (n / 3 * eta.array().square() / (n - 1)).sqrt();
    worst_rp_abc = std::max(worst_rp_abc, (p.rp_abc - 3 * s_abc).norm() / eta.maxCoeff());
  }
  std::printf(
      "ISO 9283 in 3-D, 5 poses with known offsets and scatter: AP_p and AP_xyz within %.1e m, "
      "AP_abc within %.1e rad, RP_l within %.1e and RP_abc within %.1e (relative)\n",
      worst_ap, worst_abc, worst_rp_l, worst_rp_abc);
  EXPECT_LT(worst_ap, 1e-15);
  EXPECT_LT(worst_abc, 1e-13);
  EXPECT_LT(worst_rp_l, 1e-9);
  EXPECT_LT(worst_rp_abc, 1e-9);
  // Table 4: over the path, AP_p from 13 to 65 um, |AP_a| = 1e-4 (1 + k), |AP_b| = 2e-4.
  EXPECT_NEAR(result.ap_p.max, 65e-6, 1e-15);
  EXPECT_NEAR(result.ap_p.mean, 39e-6, 1e-15);
  EXPECT_NEAR(result.ap_p.min, 13e-6, 1e-15);
  EXPECT_NEAR(result.ap_abc_abs[0].max, 5e-4, 1e-13);
  EXPECT_NEAR(result.ap_abc_abs[1].mean, 2e-4, 1e-13);
  EXPECT_NEAR(result.ap_abc_abs[2].min, 0, 1e-13);  // |3 - k| 1e-4 is 0 at k = 3
  EXPECT_NEAR(result.ap_abc_abs[2].max, 3e-4, 1e-13);

  // The outputs: one CSV row per pose, JSON and Markdown with the same numbers.
  const std::string csv = iso9283_spatial_poses_csv(result);
  EXPECT_EQ(csv.substr(0, csv.find('\n')),
            "pose,x_c,y_c,z_c,rx_c,ry_c,rz_c,x_bar,y_bar,z_bar,rx_bar,ry_bar,rz_bar,cycles,ap_x,"
            "ap_y,ap_z,ap_p,ap_a,ap_b,ap_c,l_bar,s_l,rp_l,s_a,s_b,s_c,rp_a,rp_b,rp_c");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 6);
  const nlohmann::json json = nlohmann::json::parse(iso9283_spatial_json({{"synthetic", &result}}));
  const nlohmann::json& path = json.at("iso9283_spatial").at(0);
  EXPECT_EQ(path.at("path"), "synthetic");
  EXPECT_DOUBLE_EQ(path.at("ap_p").at("max").get<double>(), result.ap_p.max);
  EXPECT_DOUBLE_EQ(path.at("rp_abc").at("c").at("min").get<double>(), result.rp_abc[2].min);
  EXPECT_EQ(path.at("poses").size(), 5u);
  const std::string table = iso9283_spatial_table_markdown({{"synthetic", &result}});
  EXPECT_NE(table.find("| synthetic | AP_p (um) | 65.0000 | 39.0000 | 13.0000 |"),
            std::string::npos)
      << table;
  EXPECT_NE(table.find("| synthetic | abs(AP_a) (mrad) | 0.5000 | 0.3000 | 0.1000 |"),
            std::string::npos)
      << table;
}

TEST(SpatialIso9283, MeanOrientationIsTheGeodesicMean) {
  // Two attained orientations far apart: their mean is the geodesic midpoint (Eigen's slerp).
  std::mt19937_64 rng(22);
  double worst_midpoint = 0, worst_mean_deviation = 0;
  for (int trial = 0; trial < 6; ++trial) {
    const Eigen::Quaterniond a = random_rotation(rng);
    const Eigen::Quaterniond b = a * Eigen::Quaterniond(Eigen::AngleAxisd(
                                         0.3 + 0.2 * trial, Vector3d(1, trial, -2).normalized()));
    SpatialPose<double> c, pa, pb;
    c.orientation = quaternion(a);
    pa.orientation = quaternion(a);
    pb.orientation = quaternion(b);
    const SpatialIso9283Result r = iso9283_spatial({c}, {{pa, pb}});
    worst_midpoint = std::max(
        worst_midpoint,
        eigen_quaternion(r.poses[0].barycentre.orientation).angularDistance(a.slerp(0.5, b)));
    // 30 orientations scattered by 0.2 rad: their deviations from the mean average to zero,
    // measured with Eigen's angle-axis.
    std::normal_distribution<double> g(0.0, 0.2);
    std::vector<SpatialPose<double>> cloud(30);
    for (SpatialPose<double>& p : cloud) {
      const Vector3d w(g(rng), g(rng), g(rng));
      p.orientation =
          quaternion(a * Eigen::Quaterniond(Eigen::AngleAxisd(w.norm(), w.normalized())));
    }
    const SpatialIso9283Result rc = iso9283_spatial({c}, {cloud});
    const Eigen::Quaterniond mean = eigen_quaternion(rc.poses[0].barycentre.orientation);
    Vector3d sum = Vector3d::Zero();
    for (const SpatialPose<double>& p : cloud) {
      const Eigen::AngleAxisd d(mean.inverse() * eigen_quaternion(p.orientation));
      sum += d.angle() * d.axis();
    }
    worst_mean_deviation = std::max(worst_mean_deviation, sum.norm() / 30);
  }
  std::printf("mean orientation: midpoint within %.1e rad of slerp; mean deviation %.1e rad\n",
              worst_midpoint, worst_mean_deviation);
  EXPECT_LT(worst_midpoint, 1e-14);
  EXPECT_LT(worst_mean_deviation, 1e-14);
}

TEST(SpatialIso9283, BadInputsNameWhat) {
  const SpatialPose<double> c;
  const auto message = [](auto&& call) {
    try {
      call();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  EXPECT_EQ(message([&] {
              iso9283_spatial({c, c}, {{c, c}});
            }),
            "iso9283_spatial: 2 commanded poses but 1 sets of attained poses");
  EXPECT_EQ(message([&] { iso9283_spatial({}, {}); }), "iso9283_spatial: no commanded pose");
  EXPECT_EQ(
      message([&] {
        iso9283_spatial({c, c}, {{c, c}, {c}});
      }),
      "iso9283_spatial: pose 1 has 1 attained poses (at least 2 needed, ISO 9283 asks for 30)");
  SpatialPose<double> bad = c;
  bad.position.y() = NAN;
  EXPECT_EQ(message([&] {
              iso9283_spatial({c, c}, {{c, c}, {c, c, bad}});
            }),
            "iso9283_spatial: attained pose 2 of pose 1 is not finite (or has a zero quaternion)");
  EXPECT_EQ(message([&] {
              iso9283_spatial({bad}, {{c, c}});
            }),
            "iso9283_spatial: commanded pose 0 is not finite (or has a zero quaternion)");
  // Turns of 2.5 rad either way about x: their mean is c, 2.5 rad from each.
  SpatialPose<double> up = c, down = c;
  up.orientation = quaternion(Eigen::Quaterniond(Eigen::AngleAxisd(2.5, Vector3d::UnitX())));
  down.orientation = quaternion(Eigen::Quaterniond(Eigen::AngleAxisd(-2.5, Vector3d::UnitX())));
  EXPECT_EQ(message([&] {
              iso9283_spatial({c}, {{c, up, down}});
            }),
            "iso9283_spatial: the attained orientations of pose 0 spread over pi / 2 or more about "
            "their mean: no unique mean");
}

// ---- IK along a path on the reference robot ----------------------------------------------------

/// The reference pose of docs/kinematics.md: 0.4 m up, tilted 10 degrees about y.
Vector4d reference_tilt() {
  return quaternion(Eigen::Quaterniond(Eigen::AngleAxisd(10 * M_PI / 180, Vector3d::UnitY())));
}

/// The worst distance of the CVODE FK at a command's joints from its poses.
struct CommandCheck {
  double position = 0, angle = 0, residual = 0;
  int pose = -1;  ///< the one farthest in position
};
CommandCheck check_on_cvode_rods(const SpatialRobotParams<double>& robot,
                                 const std::vector<SpatialPose<double>>& path,
                                 const SpatialPathCommand& command) {
  CommandCheck out;
  for (std::size_t k = 0; k < path.size(); ++k) {
    // FK at the commanded joints (cold, from straight rods), then Newton on the CVODE rods.
    const SpatialForwardSolution fk = spatial_forward_kinematics(robot, command.q[k]);
    EXPECT_TRUE(fk.summary.converged()) << "pose " << k;
    Point start;
    start.pose = fk.pose;
    for (int i = 0; i < robot.num_rods; ++i) {
      start.q[i] = fk.q(i);
      start.wrenches[i] = fk.wrenches[i];
    }
    const ReferenceFk reference = reference_forward_kinematics(robot, start);
    out.residual = std::max(out.residual, reference.residual);
    const PoseError e = pose_error(reference.x.pose, path[k]);
    if (e.position > out.position) out.pose = static_cast<int>(k);
    out.position = std::max(out.position, e.position);
    out.angle = std::max(out.angle, e.angle);
  }
  return out;
}

TEST(SpatialCommandPath, SmallCircleReachesEveryPoseOnCvodeRods) {
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  SpatialCirclePath circle;
  circle.centre = Vector3d(0, 0, 0.4);
  circle.diameter = 2e-3;
  circle.num_poses = 12;
  circle.orientation = reference_tilt();
  const std::vector<SpatialPose<double>> path = spatial_circle_path(circle);
  // Newton run to its tolerance (chord_output_share 0): every pose within 1 nm, 10 nrad.
  SpatialPathCommandOptions exact;
  exact.solver.chord_output_share = 0;
  const SpatialPathCommand command = spatial_command_path(robot, path, exact);
  ASSERT_EQ(command.q.size(), path.size());
  const CommandCheck check = check_on_cvode_rods(robot, path, command);
  const auto [lo, hi] = std::minmax_element(command.residual_evaluations.begin() + 1,
                                            command.residual_evaluations.end());
  std::printf(
      "circle of 2 mm, 12 poses, 0.4 m up, tilted 10 deg, Newton to its tolerance: CVODE FK at "
      "the commanded joints within %.2e m (pose %d), %.2e rad of the commands (CVODE residual "
      "%.1e); first pose (cold) %d residual evaluations, the others %d to %d; largest strain "
      "%.3e\n",
      check.position, check.pose, check.angle, check.residual, command.residual_evaluations[0], *lo,
      *hi, *std::max_element(command.max_strain.begin(), command.max_strain.end()));
  EXPECT_LT(check.residual, 1e-11);
  EXPECT_LT(check.position, 1e-9);
  EXPECT_LT(check.angle, 1e-8);
  // With the default options the warm IK's chord steps stop when the next one would move the
  // joints by under a tenth of position_accuracy; on this path that left one pose 3.4 nm off
  // (its scaled residual 2e-8): within 10 nm, 100 nrad.
  const SpatialPathCommand fast = spatial_command_path(robot, path);
  const CommandCheck loose = check_on_cvode_rods(robot, path, fast);
  std::printf("the same with the default chord stopping rule: within %.2e m (pose %d), %.2e rad\n",
              loose.position, loose.pose, loose.angle);
  EXPECT_LT(loose.position, 1e-8);
  EXPECT_LT(loose.angle, 1e-7);
}

TEST(SpatialCommandPath, FailuresNameThePose) {
  const SpatialRobotParams<double> robot = continuum_stewart_gough();
  const auto message = [](auto&& call) {
    try {
      call();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  SpatialPose<double> near;
  near.position = Vector3d(0, 0, 0.4);
  near.orientation = reference_tilt();
  SpatialPose<double> next = near;
  next.position.x() += 1e-3;
  // 0.9 m sideways, more than twice the rods' length from the base's centre (the rods have no
  // stroke: a platform 1 m up is reached by pushing them 0.6 m through their holes).
  SpatialPose<double> far = near;
  far.position.x() = 0.9;
  const std::string beyond = message([&] { spatial_command_path(robot, {near, next, far}); });
  std::printf("beyond reach: %s\n", beyond.c_str());
  EXPECT_EQ(beyond.rfind("pose 2 (0.9 m, 0 m, 0.4 m, 0 rad, 0.174532925 rad, 0 rad): ", 0), 0u)
      << beyond;
  // A strain limit below the path's strain.
  SpatialPathCommandOptions strict;
  strict.strain_limit = 1e-6;
  const std::string strain = message([&] { spatial_command_path(robot, {near}, strict); });
  EXPECT_NE(strain.find("pose 0 ("), std::string::npos) << strain;
  EXPECT_NE(strain.find("exceeds the limit 1e-06"), std::string::npos) << strain;
  SpatialRobotParams<double> four = robot;
  four.num_rods = 4;
  EXPECT_EQ(
      message([&] { spatial_command_path(four, {near}); }),
      "spatial_command_path: the robot has 4 rods; spatial inverse kinematics needs 3, 5 or 6");
  EXPECT_EQ(message([&] { spatial_command_path(robot, {}); }),
            "spatial_command_path: the path has no pose");
  SpatialPose<double> nan = near;
  nan.position.z() = NAN;
  EXPECT_EQ(
      message([&] { spatial_command_path(robot, {nan}); }).rfind("pose 0 (0 m, 0 m, nan m, ", 0),
      0u);
}

}  // namespace
}  // namespace pcr

namespace {

using namespace pcr;

/// A circle of the paper's diameter 0.4 m above the base, 8 poses.
std::vector<SpatialPose<double>> reference_circle() {
  SpatialCirclePath circle;
  circle.centre = Vector3<double>(0.0, 0.0, 0.4);
  circle.num_poses = 8;
  return spatial_circle_path(circle);
}

}  // namespace

/// The truth commanding itself attains its commands but for the measuring noise: AP_p is the
/// noise's mean over the cycles (sigma / sqrt(cycles) per axis) and RP_l that of |noise| (about
/// 3.6 sigma for a 3-D Gaussian). The nominal model's AP_p is what the truth's own FK at the
/// nominal's commanded joints, seen through the nominal's extrinsics, says, to the same noise.
TEST(SpatialAccuracyOnAVirtualRobot, AttainedPosesAreTheTruthsSeenThroughTheModel) {
  const SpatialRobotDescription nominal = continuum_stewart_gough_description();
  SpatialVirtualRobotOptions virtual_options;
  virtual_options.seed = 3;
  SpatialVirtualRobot robot(nominal, virtual_options);
  const double sigma = robot.noise_position();
  const std::vector<SpatialPose<double>> path = reference_circle();
  SpatialAccuracyOptions options;
  options.repeat = 10;

  const SpatialAccuracyEvaluation own =
      evaluate_on_spatial_virtual_robot(robot.truth().params, robot, path, options);
  ASSERT_EQ(own.attained.size(), path.size());
  ASSERT_EQ(own.attained[0].size(), 10u);
  EXPECT_LT(own.iso.ap_p.max, 2.0 * sigma);
  EXPECT_GT(own.iso.rp_l.min, 1.5 * sigma);
  EXPECT_LT(own.iso.rp_l.max, 7.0 * sigma);

  const SpatialAccuracyEvaluation guess =
      evaluate_on_spatial_virtual_robot(nominal.params, robot, path, options);
  // The truth's equilibria at the nominal's joints, along the path from home as the robot went.
  const SpatialExtrinsics<double>& truth = robot.truth().params.extrinsics;
  SpatialForwardSequence moves(robot.truth().params, SolverOptions(), SequenceMode::kPath);
  double worst = 0;
  for (std::size_t k = 0; k < path.size(); ++k) {
    const SpatialForwardSolution& s = moves.solve(guess.command.q[k]);
    ASSERT_TRUE(s.summary.converged()) << "pose " << k;
    const SpatialPose<double> seen = nominal.params.extrinsics.platform_from_measurement(
        truth.measurement_from_platform(s.pose));
    const double expected = (seen.position - guess.commanded[k].position).norm();
    EXPECT_GT(expected, 100 * sigma) << "pose " << k;  // the nominal's error, far above noise
    worst = std::max(worst, std::abs(guess.iso.poses[k].ap_p - expected));
  }
  std::printf(
      "truth as its own model: AP_p max %.3g m, RP_l %.3g to %.3g m (sigma %.3g m); "
      "nominal model: AP_p %.3g to %.3g m, within %.3g m of the truth's FK\n",
      own.iso.ap_p.max, own.iso.rp_l.min, own.iso.rp_l.max, sigma, guess.iso.ap_p.min,
      guess.iso.ap_p.max, worst);
  EXPECT_LT(worst, 2.0 * sigma);
}

TEST(SpatialAccuracyOnAVirtualRobot, RefusesAnotherRodCount) {
  const SpatialRobotDescription nominal = continuum_stewart_gough_description();
  SpatialVirtualRobot robot(nominal);
  SpatialRobotParams<double> three = nominal.params;
  three.num_rods = 3;
  EXPECT_THROW(evaluate_on_spatial_virtual_robot(three, robot, reference_circle()), InputError);
}
