// pcr_controller: the embedded controller example (docs/accuracy.md). Links only the header-only
// core (Eigen): a fixed-rate 1 kHz loop follows the paper's circle (diameter 3 mm, theta = 0) by
// warm-started inverse kinematics at every tick, and reports the IK time per tick.
//
//   pcr_controller [--turns N] [--period S] [--diameter M] [--rate HZ] [--realtime]
//
// Without --realtime the clock is simulated: ticks run back to back and t advances by 1 / rate.
// With it the loop sleeps until each tick's deadline (std::this_thread::sleep_until).
// Nothing in the loop allocates or throws (tests/test_controller.cpp counts the allocations).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "pcr/controller.hpp"

namespace {

struct Arguments {
  double turns = 2;
  double period_s = 2.0;  // one turn every 2 s: 4.7 mm/s along the circle
  double diameter_m = pcr::kPaperCircleDiameter;
  double rate_hz = 1000.0;
  bool realtime = false;
};

[[noreturn]] void usage(const char* message) {
  std::fprintf(stderr,
               "pcr_controller: %s\nusage: pcr_controller [--turns N] [--period S] "
               "[--diameter M] [--rate HZ] [--realtime]\n",
               message);
  std::exit(2);
}

double positive(const char* name, const char* text) {
  char* end = nullptr;
  const double value = std::strtod(text, &end);
  if (end == text || *end != '\0' || !(value > 0) || value > 1e9) {
    usage((std::string(name) + ": expected a positive number, got '" + text + "'").c_str());
  }
  return value;
}

Arguments parse(int argc, char** argv) {
  Arguments args;
  for (int i = 1; i < argc; ++i) {
    const char* a = argv[i];
    const auto value = [&]() -> const char* {
      if (i + 1 >= argc) usage((std::string(a) + ": missing value").c_str());
      return argv[++i];
    };
    if (!std::strcmp(a, "--turns"))
      args.turns = positive(a, value());
    else if (!std::strcmp(a, "--period"))
      args.period_s = positive(a, value());
    else if (!std::strcmp(a, "--diameter"))
      args.diameter_m = positive(a, value());
    else if (!std::strcmp(a, "--rate"))
      args.rate_hz = positive(a, value());
    else if (!std::strcmp(a, "--realtime"))
      args.realtime = true;
    else if (!std::strcmp(a, "--help") || !std::strcmp(a, "-h"))
      usage("help");
    else
      usage((std::string("unknown argument '") + a + "'").c_str());
  }
  return args;
}

}  // namespace

int main(int argc, char** argv) {
  using Clock = std::chrono::steady_clock;
  const Arguments args = parse(argc, argv);
  const pcr::RobotParams<double> robot = pcr::femto_3pf();
  pcr::CirclePath circle;
  circle.diameter = args.diameter_m;
  const double dt = 1.0 / args.rate_hz;
  const long ticks = std::lround(args.turns * args.period_s / dt);
  if (ticks < 1 || ticks > 100000000) usage("--turns * --period * --rate: 1 to 1e8 ticks");

  // Everything the loop touches is allocated here, before it starts.
  std::vector<double> ik_time_s(static_cast<std::size_t>(ticks));
  pcr::PathFollower<pcr::CirclePath> follower(robot, circle, args.period_s);
  if (!follower.ready()) {
    std::fprintf(stderr, "pcr_controller: the circle's first pose is out of reach\n");
    return 1;
  }
  long failures = 0, iterations = 0, misses = 0;
  pcr::ControllerTick tick;
  const Clock::time_point start = Clock::now();
  for (long k = 0; k < ticks; ++k) {
    const double t = static_cast<double>(k) * dt;
    if (args.realtime) {
      std::this_thread::sleep_until(
          start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(t)));
    }
    const Clock::time_point t0 = Clock::now();
    tick = follower.step(t);
    const double elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
    ik_time_s[static_cast<std::size_t>(k)] = elapsed;
    // tick.q would be written to the actuators here.
    if (!tick.ok()) ++failures;
    if (elapsed > dt) ++misses;
    iterations += tick.iterations;
  }
  const double wall = std::chrono::duration<double>(Clock::now() - start).count();

  std::vector<double> sorted = ik_time_s;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted[sorted.size() / 2];
  const double p99 = sorted[std::min(sorted.size() - 1, sorted.size() * 99 / 100)];
  std::printf(
      "pcr_controller: circle of diameter %.3f mm, %.3g turn(s) of %.3g s at %.0f Hz (%s)\n",
      args.diameter_m * 1e3, args.turns, args.period_s, args.rate_hz,
      args.realtime ? "real time" : "simulated clock");
  std::printf("  ticks %ld, failed %ld, Newton iterations %.2f per tick\n", ticks, failures,
              static_cast<double>(iterations) / static_cast<double>(ticks));
  std::printf(
      "  IK time per tick: median %.1f us, 99%% %.1f us, worst %.1f us; over %.0f us "
      "budget: %ld\n",
      median * 1e6, p99 * 1e6, sorted.back() * 1e6, dt * 1e6, misses);
  std::printf("  last q = (");
  for (int i = 0; i < tick.q.size(); ++i) std::printf("%s%.9f", i ? ", " : "", tick.q(i));
  std::printf(") m, wall time %.3f s\n", wall);
  return failures == 0 ? 0 : 1;
}
