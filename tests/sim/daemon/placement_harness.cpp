// SPDX-License-Identifier: Apache-2.0
#include "tests/sim/daemon/placement_harness.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <thread>

#include "daemon/sprayer/geometry.hpp"
#include "sim/plant/hydraulic_plant.hpp"
#include "vision/pipeline.hpp"
#include "vision/threshold.hpp"
#include "vision/vegetation_index.hpp"

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;

struct SeenFrame {
  double true_distance_m = 0;
  std::vector<double> density;  // row 0, one per nozzle
};

// Forwards to the simulated camera and records what each frame really imaged.
class RecordingCamera final : public io::Camera {
 public:
  RecordingCamera(io::Camera& inner, Backends& backends, const vision::PipelineConfig& vision)
      : inner_(inner), backends_(backends), pipeline_(vision) {}
  bool start() override { return inner_.start(); }
  io::FrameStatus next_frame(io::Frame& frame, std::chrono::milliseconds timeout) override {
    const io::FrameStatus status = inner_.next_frame(frame, timeout);
    if (status != io::FrameStatus::kOk) return status;
    // Where the ground was at the frame's capture time, not when this thread got to read it:
    // the plant is advanced to now, and the speed holds between the world's updates.
    SeenFrame seen;
    const auto read_at = backends_.clock->now();
    backends_.with_plant([&](sim::plant::HydraulicPlant& p) {
      const double late_s = std::chrono::duration<double>(read_at - frame.timestamp).count();
      seen.true_distance_m = p.distance_m() - p.ground_speed_m_per_s() * late_s;
    });
    const auto& result = pipeline_.process(frame.view);
    for (int c = 0; c < result.cols; ++c) seen.density.push_back(result.density(0, c));
    std::lock_guard lock(mutex_);
    frames_.push_back(std::move(seen));
    return status;
  }
  void stop() noexcept override { inner_.stop(); }
  std::string last_error() const override { return inner_.last_error(); }
  io::CameraCounters counters() const noexcept override { return inner_.counters(); }
  std::vector<SeenFrame> frames() const {
    std::lock_guard lock(mutex_);
    return frames_;
  }

 private:
  io::Camera& inner_;
  Backends& backends_;
  vision::Pipeline pipeline_;
  mutable std::mutex mutex_;
  std::vector<SeenFrame> frames_;
};

// Ground between two frames narrower than this is not judged: a valve cannot lay a dry strip
// of a few centimetres, and the tolerance is 5 cm.
constexpr double kMinGapM = 0.05;

struct Edge {
  double ground_m;  // ground position under the nozzle line
  bool opens;
};

// The spray each nozzle should lay: newest frame wins where footprints overlap; ground no
// frame saw stays dry.
std::vector<Edge> expected_edges(const std::vector<SeenFrame>& frames, std::size_t nozzle,
                                 control::GroundInterval footprint, double threshold) {
  struct Segment {
    double start, end;
    bool on;
  };
  std::vector<Segment> segments;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const double start = frames[k].true_distance_m + footprint.near_m;
    double end = frames[k].true_distance_m + footprint.far_m;
    if (k + 1 < frames.size())
      end = std::min(end, frames[k + 1].true_distance_m + footprint.near_m);
    if (end <= start) continue;
    segments.push_back({start, end, frames[k].density[nozzle] >= threshold});
  }
  std::vector<Edge> edges;
  bool on = false;
  double last_end = -1e9;
  for (const auto& s : segments) {
    if (s.start > last_end + kMinGapM && on) {  // a gap between frames: dry
      edges.push_back({last_end, false});
      on = false;
    }
    if (s.on != on) {
      edges.push_back({s.start, s.on});
      on = s.on;
    }
    last_end = s.end;
  }
  return edges;
}

}  // namespace

Config placement_config() {
  Config config = default_config();
  config.sim.speed_profile = "sine";
  config.sim.speed_min_m_per_s = 0.5;
  config.sim.speed_max_m_per_s = 2.5;
  config.sim.speed_period_s = 16;
  // Any zone past the decision threshold gets a flow only a fully open valve gives, so the
  // test judges the distance scheduling, not the duty cycle.
  config.spray.max_density = 0.001;
  config.spray.nominal_flow_l_per_min = 20;
  config.spray.decision_threshold = 0.15;
  config.spray.quantiser_levels = 0;
  config.spray.pressure_compensation = false;
  // The simulated valves' datasheet delays (plant: 15 ms + 4 ms travel / 25 ms + 6 ms).
  config.boom.valve_open_delay_s = 0.017;
  config.boom.valve_close_delay_s = 0.028;
  if (const char* hz = std::getenv("PLACEMENT_PWM_HZ")) config.pwm.frequency_hz = std::atof(hz);
  return config;
}

PlacementFigures run_placement(const Config& config, const PlacementTick& tick) {
  Options options;
  options.sim = true;

  Backends backends = make_sim_backends(config, options);
  // The valves' 50 % crossings with the distance at that instant, from the plant itself: this
  // thread's polling would date an edge as late as it was scheduled (at 2.5 m/s a 20 ms stall
  // of a loaded CI machine is 5 cm).
  backends.with_plant([](sim::plant::HydraulicPlant& p) { p.record_valve_crossings(true); });
  std::vector<sim::plant::ValveCrossing> crossings;
  vision::PipelineConfig vision = vision::default_pipeline_config();
  vision.cols = config.boom.nozzles;
  RecordingCamera camera(*backends.cameras[0], backends, vision);
  backends.cameras[0] = &camera;

  Sprayer sprayer(config, backends);
  LiveParams params = live_params_from(config);
  params.pump_enabled = true;
  params.valves_enabled = true;
  sprayer.set_params(params);
  backends.drive_world(0);
  sprayer.start();

  struct Sample {
    double distance_m;
    std::uint32_t open_mask;
  };
  std::vector<Sample> samples;
  const auto start = backends.clock->now();
  const double run_s = 24.0;
  while (true) {
    const double t = std::chrono::duration<double>(backends.clock->now() - start).count();
    if (t > run_s) break;
    backends.drive_world(t);
    Sample s{};
    backends.with_plant([&](sim::plant::HydraulicPlant& p) {
      s.distance_m = p.distance_m();
      for (int i = 0; i < p.nozzle_count(); ++i) {
        if (p.valve_opening(i) >= 0.5) s.open_mask |= 1U << i;
      }
      for (const auto& c : p.take_valve_crossings()) crossings.push_back(c);
    });
    samples.push_back(s);
    if (tick) tick(sprayer, backends, t);
    if (std::getenv("PLACEMENT_DEBUG") && samples.size() % 20 == 0) {
      const ControlStatus c = sprayer.control();
      std::printf("t %.3f odo %.3f plant %.3f dens %.3f duty %.1f open %u stale %d\n", t,
                  c.distance_m, s.distance_m, c.density[0], c.duty_pct[0], s.open_mask & 1U,
                  c.inputs_stale);
    }
    std::this_thread::sleep_for(500us);
  }
  const ControlStatus control_at_end = sprayer.control();
  double plant_distance_at_end = 0;
  backends.with_plant(
      [&](sim::plant::HydraulicPlant& p) { plant_distance_at_end = p.distance_m(); });
  std::printf("odometer %.3f m, plant %.3f m\n", control_at_end.distance_m, plant_distance_at_end);
  sprayer.stop();
  std::uint32_t final_mask = 0;
  backends.with_plant([&](sim::plant::HydraulicPlant& p) {
    p.step(0.2);  // let the spools finish moving
    for (int i = 0; i < p.nozzle_count(); ++i) {
      if (p.valve_opening(i) > 0) final_mask |= 1U << i;
    }
  });
  EXPECT_EQ(final_mask, 0U) << "valves left open after stop()";

  const auto frames = camera.frames();
  EXPECT_GT(frames.size(), 20U);
  if (frames.size() <= 20) return {};
  const auto footprint = sprayer.footprint(0);
  const double c2n = config.cameras[0].distance_to_nozzles_m;
  // Only ground the nozzles passed while the loop was running, after the first frame.
  const double ground_from = frames.front().true_distance_m + footprint.near_m;
  const double ground_to = samples.back().distance_m - c2n - 0.1;

  std::vector<double> errors_cm;
  for (std::size_t n = 0; n < static_cast<std::size_t>(config.boom.nozzles); ++n) {
    std::vector<Edge> measured;
    for (const auto& c : crossings)
      if (c.nozzle == static_cast<int>(n)) measured.push_back({c.distance_m - c2n, c.opened});
    if (n == 0 && std::getenv("PLACEMENT_DEBUG")) {
      for (const auto& f : frames)
        std::printf("frame %.3f dens %.4f %.4f %.4f %.4f\n", f.true_distance_m, f.density[0],
                    f.density[1], f.density[2], f.density[3]);
      for (const Edge& m : measured)
        std::printf("measured %s %.3f\n", m.opens ? "open" : "close", m.ground_m);
    }
    for (const Edge& e : expected_edges(frames, n, footprint, config.spray.decision_threshold)) {
      if (e.ground_m < ground_from || e.ground_m > ground_to) continue;
      double best = 1e9;
      for (const Edge& m : measured) {
        if (m.opens == e.opens && std::abs(m.ground_m - e.ground_m) < std::abs(best)) {
          best = m.ground_m - e.ground_m;
        }
      }
      errors_cm.push_back(best * 100);
      if (n == 0 && std::getenv("PLACEMENT_DEBUG")) {
        std::printf("expected %s %.3f err %.3f\n", e.opens ? "open" : "close", e.ground_m, best);
      }
      if (std::abs(best) > 0.05) {
        ADD_FAILURE() << "nozzle " << n << (e.opens ? " start" : " stop") << " at " << e.ground_m
                      << " m off by " << best * 100 << " cm";
      }
    }
  }
  EXPECT_GT(errors_cm.size(), 10U) << "too few spray edges to judge";
  if (errors_cm.size() <= 10) return {};
  std::vector<double> abs_errors;
  for (double e : errors_cm) abs_errors.push_back(std::abs(e));
  std::sort(abs_errors.begin(), abs_errors.end());
  PlacementFigures figures{abs_errors.size(), abs_errors[abs_errors.size() / 2],
                           abs_errors[abs_errors.size() * 95 / 100], abs_errors.back()};
  std::printf("placement: %zu edges, |error| median %.2f cm, p95 %.2f cm, max %.2f cm\n",
              figures.edges, figures.median_cm, figures.p95_cm, figures.max_cm);
  // Vision-to-valve latency figures (printed, not asserted: timing targets live in tools).
  std::vector<float> latencies;
  while (auto l = sprayer.latencies().try_pop()) latencies.push_back(*l);
  if (!latencies.empty()) {
    std::sort(latencies.begin(), latencies.end());
    std::printf("latency frame->scheduled: %zu frames, p50 %.2f ms, p99 %.2f ms, max %.2f ms\n",
                latencies.size(), latencies[latencies.size() / 2],
                latencies[latencies.size() * 99 / 100], latencies.back());
  }
  return figures;
}

}  // namespace weedspray::daemon
