// pcr::vision on the default robot's six 10 mm tags in a 1700 x 1700 px image (100 um/px at 0.5 m,
// noise 0.01, blur 0.8 px): AprilTag detection with the sub-pixel edge refinement, the whole
// measurement (detection, planar fit, clamps, registration), and the renderer itself.
// Counters: tags detected, corner rms (px) of the plane fit.

#include <benchmark/benchmark.h>

#include "pcr/vision/measure.hpp"
#include "pcr/vision/render.hpp"

namespace {

using namespace pcr::vision;

const char* const kMounts = PCR_SOURCE_DIR "/data/mounts-femto-3pf.json";

Scene robot_scene() {
  Scene scene;
  scene.camera.width = scene.camera.height = 1700;
  scene.camera.K << 5000, 0, 849.5, 0, 5000, 849.5, 0, 0, 1;
  scene.camera.distortion << -0.05, 0.02, 0, 0, 0;
  scene.plane = PlanePose::looking_down(0.5, 0.01, -0.008);
  scene.tags =
      mount_tags(load_mounts(kMounts), pcr::femto_3pf(), pcr::Pose2<double>{}, {}, &scene.segments);
  scene.circles.push_back(RenderCircle{Eigen::Vector2d::Zero(), 0.05});
  return scene;
}

RenderOptions render_options(int supersampling) {
  RenderOptions opt;
  opt.supersampling = supersampling;
  opt.blur_sigma_px = 0.8;
  opt.noise_sigma = 0.01;
  opt.gradient = 0.1;
  return opt;
}

void BM_DetectTags(benchmark::State& state) {
  const Scene scene = robot_scene();
  const GrayImage image = render_scene(scene, render_options(3));
  DetectorOptions options;
  options.refine = state.range(0) != 0;
  std::size_t found = 0;
  for (auto _ : state) {
    const auto detections = detect_tags(image, options, &scene.camera);
    found = detections.size();
    benchmark::DoNotOptimize(detections.data());
  }
  state.counters["tags"] = static_cast<double>(found);
}
BENCHMARK(BM_DetectTags)->ArgName("refine")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_MeasureRobot(benchmark::State& state) {
  const Scene scene = robot_scene();
  const GrayImage image = render_scene(scene, render_options(3));
  const MountLayout layout = load_mounts(kMounts);
  const pcr::RobotParams<double> design = pcr::femto_3pf();
  double rms = 0;
  for (auto _ : state) {
    const RobotMeasurement m = measure_robot(image, "bench.png", layout, scene.camera, design);
    rms = m.fit.corner_rms_px;
    benchmark::DoNotOptimize(m.limbs.data());
  }
  state.counters["corner_rms_px"] = rms;
}
BENCHMARK(BM_MeasureRobot)->Unit(benchmark::kMillisecond);

void BM_RenderScene(benchmark::State& state) {
  const Scene scene = robot_scene();
  const RenderOptions opt = render_options(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    const GrayImage image = render_scene(scene, opt);
    benchmark::DoNotOptimize(image.pixels.data());
  }
}
BENCHMARK(BM_RenderScene)
    ->ArgName("supersampling")
    ->Arg(1)
    ->Arg(3)
    ->Arg(4)
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
