// FK then IK of the default robot with the header-only core (the README's example).
#include <cstdio>
#include <pcr/pcr.hpp>

int main() {
  const pcr::RobotParams<double> robot = pcr::femto_3pf();  // the paper's 3-PF robot, SI units

  // Forward kinematics: actuator displacements q (m) -> platform pose (x m, y m, theta rad).
  pcr::JointVector q(3);
  q << 0.002, -0.001, 0.0005;
  const pcr::ForwardSolution fk = pcr::forward_kinematics(robot, q);
  if (!fk.summary.converged()) {
    std::fprintf(stderr, "FK: %s\n", pcr::to_string(fk.summary.status));
    return 1;
  }
  std::printf("pose: x = %.9f m, y = %.9f m, theta = %.9f rad (max strain %.2e)\n", fk.pose.x,
              fk.pose.y, fk.pose.theta, fk.summary.max_strain);

  // Inverse kinematics: that pose -> q, solved from the home configuration.
  const pcr::InverseSolution ik = pcr::inverse_kinematics(robot, fk.pose);
  if (!ik.summary.converged()) {
    std::fprintf(stderr, "IK: %s\n", pcr::to_string(ik.summary.status));
    return 1;
  }
  const double error = (ik.q - q).cwiseAbs().maxCoeff();
  std::printf("q: %.9f %.9f %.9f m (round-trip error %.1e m)\n", ik.q(0), ik.q(1), ik.q(2), error);
  return error < 1e-9 ? 0 : 1;
}
