// SPDX-License-Identifier: Apache-2.0
// weedspray-lab hil-frames: the camera frames of the systemd guest's hardware-in-the-loop
// scenario (tests/vm-systemd), made from the bundled labelled field photos.
//
// Each frame is one tile per nozzle zone, cut from a real photo (scaled as a whole, never
// recoloured), so the scenario knows every zone's true plant cover from the photo's hand-drawn
// mask and can judge what the installed daemon measures through V4L2. The tiles are chosen by
// the masks alone (never by what the vision library makes of them): bare tiles have no plant
// pixel, weedy ones the cover closest to a target. Frames:
//   field      every zone weedy, at different covers (the nozzles spray at different duties)
//   weeds-0-2  zones 0 and 2 weedy, 1 and 3 bare
//   weeds-1-3  the other way round
// Output in --out: NAME.yuyv (raw V4L2 YUYV, BT.601 limited range: what a camera delivers and
// what weedspray-hil writes into v4l2loopback), NAME.png (to look at) and truth.txt, one line per
// frame: "NAME cover c0 c1 ... | weed w0 w1 ... | library d0 d1 ... | tiles photo@x,y ...", where
// cover is the mask's plant share per zone, weed its weed-class share and library the vision
// library's default pipeline on the YUYV frame (for information: the scenario judges the daemon
// against cover).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "lab/commands.hpp"
#include "lab/vision_dataset.hpp"
#include "vision/pipeline.hpp"

namespace weedspray::lab {
namespace {

struct HilFramesOptions {
  std::string data_dir = WEEDSPRAY_DEFAULT_DATA_DIR;
  std::string out_dir;
  int width = 320;
  int height = 180;
  int zones = 4;
};

struct Tile {
  std::string photo;
  cv::Rect window;  // in the photo's pixels
  double cover = 0;
  double weed = 0;
  cv::Mat bgr;  // scaled to the zone's size
};

// A window of a photo with the zone's aspect ratio and its plant cover.
struct Candidate {
  std::size_t image = 0;
  cv::Rect window;
  double cover = 0;
  double surround_cover = 0;  // of the window grown by a quarter of its width on every side
  double weed = 0;            // weed-class share of the window
};

double share(const cv::Mat& integral, const cv::Rect& r) {
  const double sum = integral.at<double>(r.y + r.height, r.x + r.width) -
                     integral.at<double>(r.y, r.x + r.width) -
                     integral.at<double>(r.y + r.height, r.x) + integral.at<double>(r.y, r.x);
  return sum / static_cast<double>(r.area());
}

// BGR -> YUYV, BT.601 limited range (the V4L2 YUYV convention the vision library decodes);
// each pixel pair shares the mean of its two chroma values.
std::vector<std::uint8_t> to_yuyv(const cv::Mat& bgr) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(bgr.cols) * bgr.rows * 2);
  auto clamp8 = [](double v) {
    return static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
  };
  for (int y = 0; y < bgr.rows; ++y)
    for (int x = 0; x + 1 < bgr.cols; x += 2) {
      double luma[2], cb = 0, cr = 0;
      for (int k = 0; k < 2; ++k) {
        const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x + k);
        const double b = p[0], g = p[1], r = p[2];
        luma[k] = 16 + (65.481 * r + 128.553 * g + 24.966 * b) / 255;
        cb += (128 + (-37.797 * r - 74.203 * g + 112.0 * b) / 255) / 2;
        cr += (128 + (112.0 * r - 93.786 * g - 18.214 * b) / 255) / 2;
      }
      std::uint8_t* o = out.data() + (static_cast<std::size_t>(y) * bgr.cols + x) * 2;
      o[0] = clamp8(luma[0]);
      o[1] = clamp8(cb);
      o[2] = clamp8(luma[1]);
      o[3] = clamp8(cr);
    }
  return out;
}

int run_hil_frames(const HilFramesOptions& o) {
  if (o.out_dir.empty()) throw std::runtime_error("hil-frames: --out is required");
  if (o.width % (2 * o.zones) != 0)
    throw std::runtime_error("hil-frames: --width must split into zones of an even width");
  const std::filesystem::path peanut = std::filesystem::path(o.data_dir) / "peanut";
  const std::filesystem::path masks_dir = peanut / "masks";
  if (!std::filesystem::is_directory(masks_dir))
    throw std::runtime_error("hil-frames: " + masks_dir.string() + ": not a folder");
  std::vector<std::string> stems;
  for (const auto& entry : std::filesystem::directory_iterator(masks_dir))
    if (entry.path().extension() == ".png") stems.push_back(entry.path().stem().string());
  std::sort(stems.begin(), stems.end());
  if (stems.empty()) throw std::runtime_error("hil-frames: no masks in " + masks_dir.string());

  // One scale for every tile: the frame's height is 3/4 of a photo's (a 960x720 photo gives
  // 540-row windows, scaled by 1/3 to 180 frame rows). The masks are scanned one at a time (all
  // photos at once would take gigabytes); only the chosen tiles' photos are read.
  const int zone_w = o.width / o.zones;
  std::vector<Candidate> candidates;
  int window_w = 0, window_h = 0;
  for (std::size_t i = 0; i < stems.size(); ++i) {
    const std::filesystem::path mask_path = masks_dir / (stems[i] + ".png");
    const cv::Mat mask = cv::imread(mask_path.string(), cv::IMREAD_GRAYSCALE);
    if (mask.empty()) throw std::runtime_error("hil-frames: cannot read " + mask_path.string());
    if (window_h == 0) {
      window_h = mask.rows * 3 / 4;
      window_w = window_h * zone_w / o.height;
    }
    if (mask.rows < window_h || mask.cols < window_w) continue;
    cv::Mat plant01 = mask != 0, weed01 = mask == 2, plant_integral, weed_integral;  // 0 / 255
    plant01 /= 255;
    weed01 /= 255;
    cv::integral(plant01, plant_integral, CV_64F);
    cv::integral(weed01, weed_integral, CV_64F);
    const int stride = std::max(1, window_w / 10);
    const int margin = window_w / 4;
    for (int y = 0; y + window_h <= mask.rows; y += stride)
      for (int x = 0; x + window_w <= mask.cols; x += stride) {
        const cv::Rect window(x, y, window_w, window_h);
        const cv::Rect surround =
            (window + cv::Size(2 * margin, 2 * margin) - cv::Point(margin, margin)) &
            cv::Rect(0, 0, mask.cols, mask.rows);
        candidates.push_back({i, window, share(plant_integral, window),
                              share(plant_integral, surround), share(weed_integral, window)});
      }
  }
  // Each tile from its own photo, the first in name order that fits: bare = no plant pixel in
  // the window or around it (a mask's outline is drawn by hand: a leaf tip just outside it
  // showed in the first bare tile); weedy = the cover closest to the target.
  std::vector<bool> used(stems.size(), false);
  auto take = [&](double target) {
    const Candidate* best = nullptr;
    for (const Candidate& c : candidates) {
      if (used[c.image]) continue;
      if (target == 0 ? c.surround_cover == 0 && !best
                      : !best || std::abs(c.cover - target) < std::abs(best->cover - target))
        best = &c;
    }
    if (!best)
      throw std::runtime_error("hil-frames: no tile with plant cover near " +
                               std::to_string(target));
    used[best->image] = true;
    const LabelledImage photo =
        load_labelled_images(peanut / "images", masks_dir, {stems[best->image]}).front();
    Tile tile;
    tile.photo = photo.name;
    tile.window = best->window;
    tile.cover = best->cover;
    tile.weed = best->weed;
    cv::resize(photo.bgr(best->window), tile.bgr, cv::Size(zone_w, o.height), 0, 0, cv::INTER_AREA);
    return tile;
  };
  // Covers 10-40 %: a field's patches, not a lawn.
  const std::vector<double> field_targets{0.20, 0.40, 0.10, 0.30};
  std::vector<Tile> field, weedy, bare;
  for (int z = 0; z < o.zones; ++z) field.push_back(take(field_targets[z % 4]));
  for (int z = 0; z < (o.zones + 1) / 2; ++z) weedy.push_back(take(z % 2 ? 0.15 : 0.30));
  for (int z = 0; z < (o.zones + 1) / 2; ++z) bare.push_back(take(0.0));
  std::vector<std::pair<std::string, std::vector<Tile>>> frames{{"field", field}};
  for (int first = 0; first < 2; ++first) {
    std::vector<Tile> tiles;
    std::size_t w = 0, b = 0;
    for (int z = 0; z < o.zones; ++z) tiles.push_back(z % 2 == first ? weedy[w++] : bare[b++]);
    frames.emplace_back(first == 0 ? "weeds-0-2" : "weeds-1-3", tiles);
  }

  std::filesystem::create_directories(o.out_dir);
  std::ofstream truth(std::filesystem::path(o.out_dir) / "truth.txt");
  vision::PipelineConfig pipeline_config = vision::default_pipeline_config();
  pipeline_config.cols = o.zones;
  vision::Pipeline pipeline(pipeline_config);
  for (const auto& [name, tiles] : frames) {
    cv::Mat frame(o.height, o.width, CV_8UC3);
    for (int z = 0; z < o.zones; ++z)
      tiles[static_cast<std::size_t>(z)].bgr.copyTo(
          frame(cv::Rect(z * zone_w, 0, zone_w, o.height)));
    const std::vector<std::uint8_t> yuyv = to_yuyv(frame);
    const std::filesystem::path base = std::filesystem::path(o.out_dir) / name;
    std::ofstream(base.string() + ".yuyv", std::ios::binary)
        .write(reinterpret_cast<const char*>(yuyv.data()),
               static_cast<std::streamsize>(yuyv.size()));
    // The PNG is the YUYV decoded again (what the camera path sees), so a look at it is honest.
    cv::Mat packed(o.height, o.width, CV_8UC2, const_cast<std::uint8_t*>(yuyv.data())), seen;
    cv::cvtColor(packed, seen, cv::COLOR_YUV2BGR_YUYV);
    if (!cv::imwrite(base.string() + ".png", seen))
      throw std::runtime_error("hil-frames: cannot write " + base.string() + ".png");
    vision::ImageView view;
    view.data = yuyv.data();
    view.width = o.width;
    view.height = o.height;
    view.stride = static_cast<std::size_t>(o.width) * 2;
    view.format = vision::PixelFormat::kYuyv;
    const vision::FrameResult& result = pipeline.process(view);
    truth << name << " cover";
    for (const Tile& t : tiles) truth << ' ' << t.cover;
    truth << " | weed";
    for (const Tile& t : tiles) truth << ' ' << t.weed;
    truth << " | library";
    for (double d : result.densities()) truth << ' ' << d;
    truth << " | tiles";
    for (const Tile& t : tiles)
      truth << ' ' << t.photo << '@' << t.window.x << ',' << t.window.y << '+' << t.window.width
            << 'x' << t.window.height;
    truth << '\n';
  }
  truth.close();
  if (!truth) throw std::runtime_error("hil-frames: cannot write truth.txt in " + o.out_dir);
  std::printf("hil-frames: %zu frames %dx%d in %s (from %zu photos in %s)\n", frames.size(),
              o.width, o.height, o.out_dir.c_str(), stems.size(), peanut.c_str());
  std::ifstream again(std::filesystem::path(o.out_dir) / "truth.txt");
  for (std::string line; std::getline(again, line);) std::printf("  %s\n", line.c_str());
  return 0;
}

}  // namespace

void add_hil_frames_command(CLI::App& app) {
  auto options = std::make_shared<HilFramesOptions>();
  CLI::App* cmd = app.add_subcommand(
      "hil-frames",
      "camera frames of real field photo tiles, with each zone's true plant cover, for the "
      "systemd guest's hardware-in-the-loop scenario (tests/vm-systemd)");
  cmd->add_option("--out", options->out_dir, "folder to write NAME.yuyv, NAME.png, truth.txt")
      ->required();
  cmd->add_option("--data", options->data_dir, "the bundled data folder (holds peanut/)");
  cmd->add_option("--width", options->width, "frame width [px]");
  cmd->add_option("--height", options->height, "frame height [px]");
  cmd->add_option("--zones", options->zones, "nozzle zones across the frame")
      ->check(CLI::Range(1, 16));
  cmd->callback([options] {
    if (const char* data = std::getenv("WEEDSPRAY_DATA_DIR");
        data && options->data_dir == WEEDSPRAY_DEFAULT_DATA_DIR)
      options->data_dir = data;
    run_reporting_errors([&] { return run_hil_frames(*options); });
  });
}

}  // namespace weedspray::lab
