#include "scanstop_explorer/render.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "scanstop_common/error.h"
#include "scanstop_explorer/floor_map.h"

namespace scanstop {
namespace explorer {

namespace {

float maxFinite(const cv::Mat& v, const cv::Mat& valid) {
  float m = 0.0f;
  for (int r = 0; r < v.rows; ++r)
    for (int c = 0; c < v.cols; ++c) {
      const float x = v.at<float>(r, c);
      if (std::isfinite(x) && (valid.empty() || valid.at<uint8_t>(r, c)) && x > m) m = x;
    }
  return m;
}

/// Grey ramp of a CV_32F layer where valid; black elsewhere.
cv::Mat grey(const cv::Mat& v, const cv::Mat& valid) {
  const float m = maxFinite(v, valid);
  cv::Mat img = cv::Mat::zeros(v.size(), CV_8UC3);
  for (int r = 0; r < v.rows; ++r)
    for (int c = 0; c < v.cols; ++c) {
      const float x = v.at<float>(r, c);
      if (!std::isfinite(x) || (!valid.empty() && !valid.at<uint8_t>(r, c))) continue;
      const uint8_t g = static_cast<uint8_t>(std::lround(40.0 + 215.0 * (m > 0 ? x / m : 0.0)));
      img.at<cv::Vec3b>(r, c) = cv::Vec3b(g, g, g);
    }
  return img;
}

std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

std::string quote(const std::string& text) {
  std::string out = "\"";
  for (char ch : text) {
    if (ch == '"' || ch == '\\')
      out += '\\', out += ch;
    else if (ch == '\n')
      out += "\\n";
    else if (static_cast<unsigned char>(ch) < 0x20)
      out += ' ';
    else
      out += ch;
  }
  return out + "\"";
}

/// One legend entry: a colour swatch (filled square, dot or line) and its label.
struct LegendItem {
  cv::Scalar color;
  std::string label;
  enum Shape { kSquare, kDot, kLine, kRing } shape = kSquare;
};

/// Appends a white footer below `map` (which keeps its pixels and rows 0..map.rows-1): a scale bar
/// for `px_per_m` and the legend entries, wrapped to the image width.
cv::Mat withLegend(const cv::Mat& map, double px_per_m, const std::vector<LegendItem>& items) {
  const int font = cv::FONT_HERSHEY_SIMPLEX, line_h = 14, pad = 4;
  const double font_scale = 0.35;
  const auto textWidth = [&](const std::string& t) {
    int base = 0;
    return cv::getTextSize(t, font, font_scale, 1, &base).width;
  };
  // The scale bar: the longest of 0.1, 0.2, 0.5, 1, 2, 5, ... m that fits in a third of the width.
  double bar_m = 0.1;
  for (double m : {0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0})
    if (m * px_per_m <= map.cols / 3.0) bar_m = m;
  const int bar_px = std::max(1, static_cast<int>(std::lround(bar_m * px_per_m)));
  std::ostringstream bar_label;
  bar_label << bar_m << " m";
  // Lay the entries out left to right, wrapping; row 0 holds the scale bar first.
  struct Placed {
    int row, x;
  };
  std::vector<Placed> placed;
  int row = 0, x = pad + bar_px + 6 + textWidth(bar_label.str()) + 12;
  for (const LegendItem& it : items) {
    const int w = 12 + 3 + textWidth(it.label) + 10;
    if (x + w > map.cols - pad && x > pad) {
      ++row;
      x = pad;
    }
    placed.push_back({row, x});
    x += w;
  }
  const int footer = 2 * pad + (row + 1) * line_h;
  cv::Mat out(map.rows + footer, map.cols, CV_8UC3, cv::Scalar(255, 255, 255));
  map.copyTo(out(cv::Rect(0, 0, map.cols, map.rows)));
  const auto baseline = [&](int r) { return map.rows + pad + r * line_h + 10; };
  // Scale bar with end ticks.
  const int by = baseline(0) - 3;
  cv::line(out, {pad, by}, {pad + bar_px, by}, cv::Scalar(0, 0, 0), 2);
  cv::line(out, {pad, by - 4}, {pad, by + 2}, cv::Scalar(0, 0, 0), 1);
  cv::line(out, {pad + bar_px, by - 4}, {pad + bar_px, by + 2}, cv::Scalar(0, 0, 0), 1);
  cv::putText(out, bar_label.str(), {pad + bar_px + 6, baseline(0)}, font, font_scale, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  for (size_t i = 0; i < items.size(); ++i) {
    const LegendItem& it = items[i];
    const int x0 = placed[i].x, y = baseline(placed[i].row);
    const cv::Rect sw(x0, y - 9, 11, 11);
    switch (it.shape) {
      case LegendItem::kSquare:
        cv::rectangle(out, sw, it.color, cv::FILLED);
        cv::rectangle(out, sw, cv::Scalar(90, 90, 90), 1);
        break;
      case LegendItem::kDot:
        cv::circle(out, {x0 + 5, y - 4}, 3, it.color, cv::FILLED, cv::LINE_AA);
        break;
      case LegendItem::kLine:
        cv::line(out, {x0, y - 4}, {x0 + 11, y - 4}, it.color, 2);
        break;
      case LegendItem::kRing:
        cv::circle(out, {x0 + 5, y - 4}, 4, it.color, 1, cv::LINE_AA);
        break;
    }
    cv::putText(out, it.label, {x0 + 15, y}, font, font_scale, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  return out;
}

}  // namespace

std::vector<std::pair<std::string, cv::Mat>> renderPlanImages(const PlanResult& res, int scale) {
  std::vector<std::pair<std::string, cv::Mat>> out;
  if (res.states.empty()) return out;
  scale = std::max(1, scale);
  const cv::Mat none;
  // Floor.
  cv::Mat floor = cv::Mat::zeros(res.states.size(), CV_8UC3);
  floor.setTo(cv::Scalar(128, 128, 128), res.states == kFloor);
  floor.setTo(cv::Scalar(0, 0, 220), res.states == kObstacle);
  if (!res.open.empty()) floor.setTo(cv::Scalar(0, 160, 255), res.open);  // open cells (termination test)
  out.emplace_back("floor", floor);
  if (!res.sq_dt.empty()) {
    cv::Mat d;
    res.sq_dt.convertTo(d, CV_32F);
    cv::sqrt(d, d);
    cv::Mat dimg = grey(d, res.accessible);
    if (!res.skeleton.empty()) dimg.setTo(cv::Scalar(255, 120, 0), res.skeleton);
    if (!res.anchors.empty()) dimg.setTo(cv::Scalar(0, 255, 255), res.anchors);
    out.emplace_back("distance", dimg);
  }
  if (!res.cost_map.cost.empty()) out.emplace_back("cost", grey(res.cost_map.cost, res.cost_map.predecessor >= 0));
  if (!res.knowledge.empty()) out.emplace_back("knowledge", grey(res.knowledge, res.states != kUnknown));
  if (!res.evaluation.empty()) out.emplace_back("evaluation", grey(res.evaluation, res.evaluation > 0));

  const GridGeometry& g = res.geometry;
  auto px = [&](const Eigen::Vector2d& p_map) {
    const Eigen::Vector2d q = g.toGrid(p_map) * scale;
    return cv::Point(static_cast<int>(std::lround(q.x())), static_cast<int>(std::lround(q.y())));
  };
  auto pxCell = [&](const Eigen::Vector2d& p_cells) {
    return cv::Point(static_cast<int>(std::lround(p_cells.x() * scale)),
                     static_cast<int>(std::lround(p_cells.y() * scale)));
  };
  for (auto& [name, img] : out) {
    cv::resize(img, img, cv::Size(), scale, scale, cv::INTER_NEAREST);
    for (size_t i = 1; i < res.cost_map.nodes.size(); ++i)
      cv::circle(img, pxCell(res.cost_map.nodes[i].pos), std::max(1, scale), cv::Scalar(0, 0, 255), cv::FILLED);
    for (size_t i = 1; i < res.path.size(); ++i)
      cv::line(img, px(res.path[i - 1]), px(res.path[i]), cv::Scalar(255, 255, 0), std::max(1, scale / 2));
    if (res.target_cell.x >= 0)
      cv::circle(img, px(res.target), 2 * scale, cv::Scalar(255, 0, 255), std::max(1, scale / 2));
    const Eigen::Vector2d robot(res.robot.x, res.robot.y);
    const Eigen::Vector2d head = robot + 0.4 * Eigen::Vector2d(std::cos(res.robot.yaw), std::sin(res.robot.yaw));
    cv::circle(img, px(robot), std::max(2, static_cast<int>(std::lround(0.2 / g.resolution * scale))),
               cv::Scalar(0, 200, 0), std::max(1, scale / 2));
    cv::line(img, px(robot), px(head), cv::Scalar(0, 200, 0), std::max(1, scale / 2));
    cv::flip(img, img, 0);  // row 0 is the lowest y: put north up
    // The legend: what this layer's colours mean, then what every layer has drawn in.
    std::vector<LegendItem> items;
    if (name == "floor") {
      items = {
          {cv::Scalar(128, 128, 128), "floor"}, {cv::Scalar(0, 0, 220), "obstacle"}, {cv::Scalar(0, 0, 0), "unknown"}};
      if (!res.open.empty()) items.push_back({cv::Scalar(0, 160, 255), "open cell"});
    } else if (name == "distance") {
      items = {{cv::Scalar(200, 200, 200), "brighter: farther from obstacles"},
               {cv::Scalar(255, 120, 0), "skeleton"},
               {cv::Scalar(0, 255, 255), "anchor"}};
    } else {
      const char* what = name == "cost"        ? "brighter: farther to go"
                         : name == "knowledge" ? "brighter: better known"
                                               : "brighter: better target";
      items = {{cv::Scalar(200, 200, 200), what}};
    }
    items.push_back({cv::Scalar(0, 200, 0), "robot", LegendItem::kRing});
    items.push_back({cv::Scalar(0, 0, 255), "landmark", LegendItem::kDot});
    items.push_back({cv::Scalar(255, 255, 0), "path", LegendItem::kLine});
    items.push_back({cv::Scalar(255, 0, 255), "target", LegendItem::kRing});
    img = withLegend(img, scale / g.resolution, items);
  }
  return out;
}

void writePlanImages(const PlanResult& result, const std::string& dir, const std::string& prefix, int scale) {
  for (const auto& [name, img] : renderPlanImages(result, scale)) {
    const std::string path = dir + "/" + prefix + name + ".png";
    bool ok = false;
    try {
      ok = cv::imwrite(path, img);
    } catch (const cv::Exception& e) {
      throw IoError(path, std::string("cannot write PNG: ") + e.what());
    }
    if (!ok) throw IoError(path, "cannot write PNG (does the directory exist and is it writable?)");
  }
}

std::string floorMapPng(const PlanResult& r) {
  // map_server's trinary convention: free 254, occupied 0, unknown 205; row 0 is the highest y.
  cv::Mat img(r.states.size(), CV_8UC1, cv::Scalar(205));
  img.setTo(cv::Scalar(254), r.states == kFloor);
  img.setTo(cv::Scalar(0), r.states == kObstacle);
  cv::flip(img, img, 0);
  std::vector<uchar> buffer;
  if (!cv::imencode(".png", img, buffer)) throw IoError("floor map", "PNG encoding failed");
  return std::string(buffer.begin(), buffer.end());
}

std::string floorMapYaml(const PlanResult& r, const std::string& image) {
  std::ostringstream s;
  s.precision(10);
  s << "# The explorer's floor grid (map_server format): floor 254, obstacle 0, unknown 205, north up.\n"
    << "image: " << image << "\n"
    << "resolution: " << r.geometry.resolution << "\n"
    << "origin: [" << r.geometry.origin_x << ", " << r.geometry.origin_y << ", 0.0]\n"
    << "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
    << "width: " << r.geometry.width << "\nheight: " << r.geometry.height << "\n";
  return s.str();
}

std::string planToJson(const PlanResult& r) {
  std::ostringstream s;
  s << "{\"success\": " << (r.success ? "true" : "false") << ", \"message\": " << quote(r.message)
    << ", \"complete\": " << (r.complete ? "true" : "false") << ", \"complete_reason\": " << quote(r.complete_reason)
    << ", \"target\": {\"x\": " << num(r.target.x()) << ", \"y\": " << num(r.target.y()) << "}"
    << ", \"score\": " << num(r.score) << ", \"cost_m\": " << num(r.target_cost_m)
    << ", \"target_moved_m\": " << num(r.target_moved_m) << ", \"target_gain_m2\": " << num(r.target_gain_m2)
    << ", \"coverage\": " << num(r.coverage) << ", \"floor_area_m2\": " << num(r.floor_area_m2)
    << ", \"accessible_area_m2\": " << num(r.accessible_area_m2)
    << ", \"reachable_area_m2\": " << num(r.reachable_area_m2) << ", \"cut_off_area_m2\": " << num(r.cut_off_area_m2)
    << ", \"open_cells\": " << r.open_cells << ", \"open_cells_ignored\": " << r.open_cells_ignored
    << ", \"open_beyond_reach\": " << r.open_beyond_reach
    << ", \"landmarks\": " << (r.cost_map.nodes.empty() ? 0 : r.cost_map.nodes.size() - 1)
    << ", \"coverage_landmarks\": " << r.cost_map.coverage_landmarks << ", \"path\": [";
  for (size_t i = 0; i < r.path.size(); ++i)
    s << (i ? ", " : "") << "{\"x\": " << num(r.path[i].x()) << ", \"y\": " << num(r.path[i].y())
      << ", \"scan\": " << (r.scan_at[i] ? "true" : "false")
      << (i < r.clearance_m.size() ? ", \"clearance_m\": " + num(r.clearance_m[i]) : std::string()) << "}";
  s << "], \"timings_ms\": {";
  for (size_t i = 0; i < r.timings_ms.size(); ++i)
    s << (i ? ", " : "") << quote(r.timings_ms[i].first) << ": " << num(r.timings_ms[i].second);
  s << "}}";
  return s.str();
}

std::string pathToCsv(const PlanResult& r) {
  std::ostringstream s;
  s.precision(10);
  s << "x,y,scan\n";
  for (size_t i = 0; i < r.path.size(); ++i)
    s << r.path[i].x() << "," << r.path[i].y() << "," << (r.scan_at[i] ? 1 : 0) << "\n";
  return s.str();
}

std::vector<int8_t> statesToOccupancy(const cv::Mat& states) {
  std::vector<int8_t> out(states.total(), -1);
  size_t i = 0;
  for (int r = 0; r < states.rows; ++r)
    for (int c = 0; c < states.cols; ++c, ++i) {
      const uint8_t s = states.at<uint8_t>(r, c);
      out[i] = s == kFloor ? 0 : (s == kObstacle ? 100 : -1);
    }
  return out;
}

std::vector<int8_t> accessibleToOccupancy(const cv::Mat& states, const cv::Mat& accessible) {
  std::vector<int8_t> out = statesToOccupancy(states);
  size_t i = 0;
  for (int r = 0; r < states.rows; ++r)
    for (int c = 0; c < states.cols; ++c, ++i)
      if (out[i] == 0) out[i] = accessible.at<uint8_t>(r, c) ? 0 : 60;
  return out;
}

std::vector<int8_t> scaledToOccupancy(const cv::Mat& values, const cv::Mat& valid) {
  const float m = maxFinite(values, valid);
  std::vector<int8_t> out(values.total(), -1);
  size_t i = 0;
  for (int r = 0; r < values.rows; ++r)
    for (int c = 0; c < values.cols; ++c, ++i) {
      const float v = values.at<float>(r, c);
      if (!std::isfinite(v) || (!valid.empty() && !valid.at<uint8_t>(r, c))) continue;
      out[i] = static_cast<int8_t>(std::lround(m > 0 ? 100.0 * v / m : 0.0));
    }
  return out;
}

}  // namespace explorer
}  // namespace scanstop
