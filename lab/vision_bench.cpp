// SPDX-License-Identifier: Apache-2.0
// bench-vision: time per 1280x800 BGR frame of the default pipeline, against a straightforward
// OpenCV-primitives version of the same pipeline (cv::transform, cv::threshold with Otsu,
// cv::countNonZero per zone); with --pipeline, of a weed source (inter_row, dnn, hybrid, plants,
// dnn_vegetation).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "daemon/config/config.hpp"
#include "daemon/config/vision_config.hpp"
#include "daemon/sprayer/snapshot_handoff.hpp"
#include "lab/vision_dataset.hpp"
#include "lab/vision_tools.hpp"
#include "lab/weed_eval_command.hpp"
#include "lab/weed_model.hpp"
#include "vision/pipeline.hpp"

namespace weedspray::lab {
namespace {

constexpr int kFrameWidth = 1280;
constexpr int kFrameHeight = 800;

struct BenchOptions {
  std::string image;
  std::string pipeline = "vegetation";
  std::string model;
  int crop_margin_px = kDefaultCropMarginPx;
  int frames = 500;
  int warmup = 20;
  double frame_mm_per_px = -1.0;  // < 0: the default camera's ground scale
  bool json = false;
};

// A seeded synthetic field: noisy brown soil with rows of green plants and scattered weeds.
cv::Mat synthetic_field() {
  cv::Mat frame(kFrameHeight, kFrameWidth, CV_8UC3, cv::Scalar(70, 100, 130));
  cv::RNG random(20240601);
  cv::Mat noise(frame.size(), CV_8UC3);
  random.fill(noise, cv::RNG::NORMAL, cv::Scalar::all(0), cv::Scalar::all(12));
  frame += noise;
  for (int row = 0; row < 4; ++row) {
    for (int y = 20; y < kFrameHeight; y += 60) {
      const cv::Point centre(160 + row * 320 + random.uniform(-20, 20), y);
      cv::ellipse(frame, centre, cv::Size(random.uniform(15, 40), random.uniform(10, 25)),
                  random.uniform(0, 180), 0, 360, cv::Scalar(40, 150, 60), cv::FILLED);
    }
  }
  for (int weed = 0; weed < 150; ++weed) {
    cv::circle(frame, cv::Point(random.uniform(0, kFrameWidth), random.uniform(0, kFrameHeight)),
               random.uniform(3, 12), cv::Scalar(50, 130, 70), cv::FILLED);
  }
  return frame;
}

// The frame to time: --image scaled to 1280x800 (a real soil/plant mix), else the first
// bundled field image under $WEEDSPRAY_DATA_DIR, else the synthetic field.
cv::Mat bench_frame(const std::string& image_path, std::string& source) {
  std::filesystem::path path = image_path;
  if (path.empty()) {
    if (const char* data_dir = std::getenv("WEEDSPRAY_DATA_DIR")) {
      const std::filesystem::path images = std::filesystem::path(data_dir) / "ews-train" / "images";
      std::vector<std::filesystem::path> candidates;
      if (std::filesystem::is_directory(images)) {
        for (const auto& entry : std::filesystem::directory_iterator(images)) {
          candidates.push_back(entry.path());
        }
      }
      if (!candidates.empty()) path = *std::min_element(candidates.begin(), candidates.end());
    }
  }
  if (path.empty()) {
    source = "synthetic field (seeded)";
    return synthetic_field();
  }
  source = path.string();
  cv::Mat frame;
  cv::resize(read_bgr_image(path), frame, cv::Size(kFrameWidth, kFrameHeight), 0, 0,
             cv::INTER_LINEAR);
  return frame;
}

struct Timing {
  double median_ms = 0;
  double p99_ms = 0;
  double cpu_median_ms = 0;  // thread CPU time: what the frame costs without preemption
};

double thread_cpu_ms() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return now.tv_sec * 1e3 + now.tv_nsec / 1e6;
}

template <typename Function>
Timing time_frames(int warmup, int frames, Function&& function) {
  for (int i = 0; i < warmup; ++i) function();
  std::vector<double> milliseconds(frames);
  std::vector<double> cpu_milliseconds(frames);
  for (int i = 0; i < frames; ++i) {
    const double cpu_start = thread_cpu_ms();
    const auto start = std::chrono::steady_clock::now();
    function();
    const auto stop = std::chrono::steady_clock::now();
    cpu_milliseconds[i] = thread_cpu_ms() - cpu_start;
    milliseconds[i] = std::chrono::duration<double, std::milli>(stop - start).count();
  }
  std::sort(milliseconds.begin(), milliseconds.end());
  std::sort(cpu_milliseconds.begin(), cpu_milliseconds.end());
  return {milliseconds[milliseconds.size() / 2],
          milliseconds[std::min(milliseconds.size() - 1, milliseconds.size() * 99 / 100)],
          cpu_milliseconds[cpu_milliseconds.size() / 2]};
}

// The same pipeline from OpenCV primitives: CIVE by cv::transform (same fixed-point
// coefficients, as floats), Otsu by cv::threshold, densities by cv::countNonZero per zone.
struct OpenCvBaseline {
  vision::PipelineConfig config;
  cv::Mat index, mask;
  std::vector<double> densities;
  void run(const cv::Mat& bgr) {
    const cv::Matx14f cive(-25.f / 128, 52.f / 128, -28.f / 128,
                           static_cast<float>(vision::kCiveOffset) / 128 - 0.5f);
    cv::transform(bgr, index, cive);
    cv::threshold(index, mask, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
    densities.assign(config.rows * config.cols, 0.0);
    for (int row = 0; row < config.rows; ++row) {
      for (int col = 0; col < config.cols; ++col) {
        const cv::Rect zone(col * mask.cols / config.cols, row * mask.rows / config.rows,
                            (col + 1) * mask.cols / config.cols - col * mask.cols / config.cols,
                            (row + 1) * mask.rows / config.rows - row * mask.rows / config.rows);
        densities[row * config.cols + col] =
            static_cast<double>(cv::countNonZero(mask(zone))) / zone.area();
      }
    }
  }
};

int run_bench(const BenchOptions& options) {
  if (options.frames < 1 || options.warmup < 0) {
    throw std::runtime_error("--frames must be >= 1 and --warmup >= 0");
  }
  cv::setNumThreads(1);  // single thread, like the daemon's vision worker
  std::string source;
  const cv::Mat frame = bench_frame(options.image, source);
  vision::PipelineConfig config = vision::default_pipeline_config();
  config.rows = 2;  // the wheat paper's 2 x 4 zone grid
  config.cols = 4;
  config.weed_source = parse_weed_source_option("--pipeline", options.pipeline);
  config.crop_margin_px = options.crop_margin_px;
  // The frame's ground scale decides the network input (the daemon resamples to the model's
  // scale): the default camera's unless given; 0 squeezes the frame to the spec's input size.
  config.frame_mm_per_px =
      options.frame_mm_per_px >= 0
          ? options.frame_mm_per_px
          : daemon::camera_ground_mm_per_px(daemon::default_config().cameras.front());
  config.min_plant_px = vision::area_in_pixels(daemon::default_config().vision.min_plant_cm2,
                                               config.frame_mm_per_px, kDefaultMinPlantPx);
  WeedModel model;
  if (!options.model.empty()) {
    model = read_weed_model(options.model);
    config.dnn = model.spec;
  } else if (vision::needs_model(config.weed_source)) {
    throw std::runtime_error("--pipeline " + options.pipeline + " needs --model FILE");
  }
  vision::Pipeline pipeline(config, model.onnx);
  const vision::ImageView view{frame.data, frame.cols, frame.rows, frame.step[0],
                               vision::PixelFormat::kBgr24};
  const Timing ours = time_frames(options.warmup, options.frames, [&] { pipeline.process(view); });
  // The OpenCV baseline is the vegetation pipeline's; the weed sources have none.
  const bool vegetation = config.weed_source == vision::WeedSource::kVegetation;
  OpenCvBaseline baseline{config, {}, {}, {}};
  const Timing opencv =
      vegetation ? time_frames(options.warmup, options.frames, [&] { baseline.run(frame); })
                 : Timing{};
  const vision::FrameResult& result = pipeline.process(view);
  if (!pipeline.last_frame_ok()) throw std::runtime_error(pipeline.last_error());
  // The live view's costs, as the daemon pays them: the camera thread's copy of frame, class
  // map and densities when a snapshot is asked for, and the encoder thread's overlay + PNG.
  daemon::SnapshotHandoff handoff;
  const Timing handoff_fill = time_frames(2, std::min(options.frames, 50), [&] {
    handoff.request(daemon::SnapshotHandoff::packed_bytes(view), pipeline.class_map_pixels());
    handoff.fill(view, {}, pipeline, result);
    handoff.release();
  });
  handoff.request(daemon::SnapshotHandoff::packed_bytes(view), pipeline.class_map_pixels());
  handoff.fill(view, {}, pipeline, result);
  const std::vector<double> duties(static_cast<std::size_t>(config.cols), 50.0);
  std::size_t png_bytes = 0;
  const Timing overlay = time_frames(1, std::min(options.frames, 10), [&] {
    png_bytes = daemon::overlay_png(*handoff.ready(), duties).size();
  });
  const std::string name(to_string(config.weed_source));
  const vision::NetworkInputSize input =
      vision::network_input_size(config.dnn, config.frame_mm_per_px, kFrameWidth, kFrameHeight);
  if (options.json) {
    std::printf(
        "{\"frame\": \"%dx%d\", \"pipeline\": \"%s\", \"threads\": 1, "
        "\"pipeline_ms_median\": %.4f, \"pipeline_ms_p99\": %.4f, "
        "\"pipeline_thread_cpu_ms_median\": %.4f",
        kFrameWidth, kFrameHeight, name.c_str(), ours.median_ms, ours.p99_ms, ours.cpu_median_ms);
    if (vision::needs_model(config.weed_source)) {
      std::printf(
          ", \"frame_mm_per_px\": %.4f, \"model_mm_per_px\": %.4f, \"model_input\": \"%dx%d\"",
          config.frame_mm_per_px, config.dnn.ground_mm_per_px, input.width, input.height);
    }
    if (vegetation) std::printf(", \"opencv_baseline_ms_median\": %.4f", opencv.median_ms);
    std::printf(", \"snapshot_copy_ms_median\": %.4f, \"snapshot_png_ms_median\": %.4f}\n",
                handoff_fill.median_ms, overlay.median_ms);
    return 0;
  }
  std::printf(
      "frame %dx%d BGR from %s\nindex %s, threshold %s, %dx%d zones, weed source %s, %d frames "
      "after %d warm-up, one thread\n",
      kFrameWidth, kFrameHeight, source.c_str(), std::string(to_string(config.index)).c_str(),
      std::string(to_string(config.threshold)).c_str(), config.rows, config.cols, name.c_str(),
      options.frames, options.warmup);
  if (vision::needs_model(config.weed_source)) {
    std::printf("model %s (%.2f mm/px) on frames of %.2f mm/px: network input %dx%d%s\n",
                options.model.c_str(), config.dnn.ground_mm_per_px, config.frame_mm_per_px,
                input.width, input.height,
                model.spec_from_json ? "" : " (no .json beside it: default spec)");
  }
  std::printf(
      "weedspray pipeline: median %.3f ms, p99 %.3f ms, thread CPU median %.3f ms "
      "(threshold %d, vegetation %.1f%%)\n",
      ours.median_ms, ours.p99_ms, ours.cpu_median_ms, result.threshold,
      100.0 * result.vegetation_fraction);
  if (vegetation) {
    std::printf("OpenCV baseline:    median %.3f ms, p99 %.3f ms, thread CPU median %.3f ms\n",
                opencv.median_ms, opencv.p99_ms, opencv.cpu_median_ms);
  }
  std::printf(
      "live view: camera-thread copy median %.3f ms, p99 %.3f ms; overlay + PNG median %.1f ms, "
      "p99 %.1f ms, thread CPU median %.1f ms (%zu KiB)\n",
      handoff_fill.median_ms, handoff_fill.p99_ms, overlay.median_ms, overlay.p99_ms,
      overlay.cpu_median_ms, png_bytes / 1024);
  return 0;
}

}  // namespace

void add_bench_vision_command(CLI::App& app) {
  auto options = std::make_shared<BenchOptions>();
  CLI::App* bench = app.add_subcommand(
      "bench-vision",
      "Time a vision pipeline on 1280x800 frames, one thread (the default one vs an OpenCV "
      "baseline, or a weed source)");
  bench
      ->add_option("--pipeline", options->pipeline,
                   "Weed source (vegetation is the default pipeline): " + weed_source_list())
      ->capture_default_str();
  bench
      ->add_option("--model", options->model,
                   "ONNX weed model for the sources that need one (spec from FILE.json)")
      ->check(CLI::ExistingFile);
  bench->add_option("--crop-margin-px", options->crop_margin_px, "hybrid: crop margin in pixels")
      ->capture_default_str();
  bench
      ->add_option("--image", options->image,
                   "Field image scaled to 1280x800 (default: the first image of "
                   "$WEEDSPRAY_DATA_DIR/ews-train/images, else a seeded synthetic field)")
      ->check(CLI::ExistingFile);
  bench
      ->add_option("--frame-mm-per-px", options->frame_mm_per_px,
                   "Ground mm per frame pixel (default: the default camera's, from its mount "
                   "height, tilt and field of view; 0: squeeze the frame to the model's input)")
      ->check(CLI::NonNegativeNumber);
  bench->add_option("--frames", options->frames, "Timed frames")->capture_default_str();
  bench->add_option("--warmup", options->warmup, "Untimed warm-up frames")->capture_default_str();
  bench->add_flag("--json", options->json, "Print one JSON object");
  bench->callback([options] {
    try {
      run_bench(*options);
    } catch (const std::exception& error) {
      std::cerr << "weedspray-lab bench-vision: " << error.what() << "\n";
      throw CLI::RuntimeError(1);
    }
  });
}

}  // namespace weedspray::lab
