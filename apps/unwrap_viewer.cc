#include "apps/unwrap_viewer.h"

#include <opencv2/highgui.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "core/error.h"
#include "core/io.h"

namespace hovs::apps {

std::string LayoutYaml(const unwrap::Layout& layout) {
  std::ostringstream os;
  os << "# hovs layout (angles in degrees, sizes in pixels)\nname: " << layout.name << "\nviews:\n";
  for (const auto& v : layout.views) {
    os << "  - {name: " << v.name << ", type: " << ToString(v.type) << ", width: " << v.width
       << ", height: " << v.height;
    if (v.type == ViewProjection::kPerspective) {
      os << ", yaw: " << v.yaw_deg << ", pitch: " << v.pitch_deg << ", roll: " << v.roll_deg
         << ", hfov: " << v.hfov_deg;
    } else {
      os << ", elevation_min: " << v.elevation_min_deg << ", elevation_max: " << v.elevation_max_deg
         << ", azimuth_centre: " << v.azimuth_centre_deg << ", azimuth_span: " << v.azimuth_span_deg;
    }
    os << "}\n";
  }
  return os.str();
}

namespace {

struct Panel {
  const AnyModel* model;
  unwrap::Layout layout;
  unwrap::ImageView frame;
  int view = 0;
  int yaw = 0, pitch = 0, roll = 0, fov = 0;  // slider positions
  bool dirty = true;
};

void Load(Panel* p) {
  const auto& v = p->layout.views[p->view];
  if (v.type == ViewProjection::kPerspective) {
    p->yaw = int(std::lround(std::fmod(v.yaw_deg + 720, 360)));
    p->pitch = int(std::lround(v.pitch_deg)) + 90;
    p->roll = int(std::lround(v.roll_deg)) + 180;
    p->fov = int(std::lround(v.hfov_deg));
  } else {
    p->yaw = int(std::lround(std::fmod(v.azimuth_centre_deg + 720, 360)));
    p->pitch = int(std::lround(v.elevation_max_deg)) + 90;
    p->roll = int(std::lround(v.elevation_min_deg)) + 180;
    p->fov = int(std::lround(v.azimuth_span_deg / 2));
  }
}

// Slider positions -> the view; invalid combinations are clamped into the valid domain.
void Store(Panel* p) {
  auto& v = p->layout.views[p->view];
  if (v.type == ViewProjection::kPerspective) {
    v.yaw_deg = p->yaw, v.pitch_deg = p->pitch - 90, v.roll_deg = p->roll - 180;
    v.hfov_deg = std::clamp(p->fov, 5, 170);
  } else {
    v.azimuth_centre_deg = p->yaw;
    v.elevation_max_deg = std::clamp(p->pitch - 90, -88, 88);
    v.elevation_min_deg = std::clamp(p->roll - 180, -89, int(v.elevation_max_deg) - 1);
    v.azimuth_span_deg = std::clamp(2 * p->fov, 10, 360);
  }
}

}  // namespace

void RunUnwrapViewer(const AnyModel& model, unwrap::Layout layout, const unwrap::ImageView& frame,
                     const std::filesystem::path& layout_out) {
  const char* display = std::getenv("DISPLAY");
  HOVS_REQUIRE(display != nullptr && *display, "hovs unwrap --interactive",
               "needs a display (DISPLAY is not set); on a headless machine use xvfb-run or drop --interactive");
  Panel p{&model, std::move(layout), frame};
  Load(&p);
  const std::string win = "hovs unwrap";
  cv::namedWindow(win, cv::WINDOW_NORMAL);
  const int nviews = static_cast<int>(p.layout.views.size());
  const auto changed = [](int, void* data) { static_cast<Panel*>(data)->dirty = true; };
  const auto view_changed = [](int, void* data) {
    auto* q = static_cast<Panel*>(data);
    Load(q);
    cv::setTrackbarPos("yaw | az", "hovs unwrap", q->yaw);
    cv::setTrackbarPos("pitch+90 | el_max+90", "hovs unwrap", q->pitch);
    cv::setTrackbarPos("roll+180 | el_min+180", "hovs unwrap", q->roll);
    cv::setTrackbarPos("hfov | span/2", "hovs unwrap", q->fov);
    q->dirty = true;
  };
  if (nviews > 1) cv::createTrackbar("view", win, &p.view, nviews - 1, view_changed, &p);
  cv::createTrackbar("yaw | az", win, &p.yaw, 359, changed, &p);
  cv::createTrackbar("pitch+90 | el_max+90", win, &p.pitch, 180, changed, &p);
  cv::createTrackbar("roll+180 | el_min+180", win, &p.roll, 360, changed, &p);
  cv::createTrackbar("hfov | span/2", win, &p.fov, 180, changed, &p);
  cv::Mat shown;
  for (;;) {
    if (p.dirty) {
      p.dirty = false;
      Store(&p);
      unwrap::Layout one;
      one.name = p.layout.name;
      one.views = {p.layout.views[p.view]};
      try {
        const unwrap::RemapTable t = unwrap::BuildRemapTable(model, one, {});
        unwrap::Remapper r(t);
        unwrap::Image8 out;
        r.RunView(p.frame, unwrap::Interpolation::kBilinear, 0, &out);
        cv::Mat m(out.height, out.width, out.channels == 3 ? CV_8UC3 : CV_8UC1, out.data.data());
        if (out.channels == 3)
          cv::cvtColor(m, shown, cv::COLOR_RGB2BGR);
        else
          shown = m.clone();
        std::printf("\r%s: %s            ", one.views[0].name.c_str(),
                    LayoutYaml(one).substr(LayoutYaml(one).find("{")).c_str());
        std::fflush(stdout);
      } catch (const Error& e) { std::fprintf(stderr, "\n%s\n", e.what()); }
      if (!shown.empty()) cv::imshow(win, shown);
    }
    const int key = cv::waitKey(30);
    if (key == 'q' || key == 27) break;
    if (key == 's') {
      CheckOutputFile(layout_out, "# hovs layout", "a hovs layout");
      WriteFileAtomic(layout_out, LayoutYaml(p.layout));
      std::printf("\nlayout saved to %s\n", layout_out.string().c_str());
    }
    if (cv::getWindowProperty(win, cv::WND_PROP_VISIBLE) < 1) break;
  }
  cv::destroyAllWindows();
}

}  // namespace hovs::apps
