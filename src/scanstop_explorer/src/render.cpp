#include "scanstop_explorer/render.h"

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
    if (ch == '"' || ch == '\\') out += '\\', out += ch;
    else if (ch == '\n') out += "\\n";
    else if (static_cast<unsigned char>(ch) < 0x20) out += ' ';
    else out += ch;
  }
  return out + "\"";
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
    return cv::Point(static_cast<int>(std::lround(p_cells.x() * scale)), static_cast<int>(std::lround(p_cells.y() * scale)));
  };
  for (auto& [name, img] : out) {
    cv::resize(img, img, cv::Size(), scale, scale, cv::INTER_NEAREST);
    for (size_t i = 1; i < res.cost_map.nodes.size(); ++i)
      cv::circle(img, pxCell(res.cost_map.nodes[i].pos), std::max(1, scale), cv::Scalar(0, 0, 255), cv::FILLED);
    for (size_t i = 1; i < res.path.size(); ++i)
      cv::line(img, px(res.path[i - 1]), px(res.path[i]), cv::Scalar(255, 255, 0), std::max(1, scale / 2));
    if (res.target_cell.x >= 0) cv::circle(img, px(res.target), 2 * scale, cv::Scalar(255, 0, 255), std::max(1, scale / 2));
    const Eigen::Vector2d robot(res.robot.x, res.robot.y);
    const Eigen::Vector2d head = robot + 0.4 * Eigen::Vector2d(std::cos(res.robot.yaw), std::sin(res.robot.yaw));
    cv::circle(img, px(robot), std::max(2, static_cast<int>(std::lround(0.2 / g.resolution * scale))), cv::Scalar(0, 200, 0),
               std::max(1, scale / 2));
    cv::line(img, px(robot), px(head), cv::Scalar(0, 200, 0), std::max(1, scale / 2));
    cv::flip(img, img, 0);  // row 0 is the lowest y: put north up
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

std::string planToJson(const PlanResult& r) {
  std::ostringstream s;
  s << "{\"success\": " << (r.success ? "true" : "false") << ", \"message\": " << quote(r.message)
    << ", \"complete\": " << (r.complete ? "true" : "false") << ", \"complete_reason\": " << quote(r.complete_reason)
    << ", \"target\": {\"x\": " << num(r.target.x()) << ", \"y\": " << num(r.target.y()) << "}"
    << ", \"score\": " << num(r.score) << ", \"cost_m\": " << num(r.target_cost_m)
    << ", \"target_moved_m\": " << num(r.target_moved_m) << ", \"coverage\": " << num(r.coverage)
    << ", \"floor_area_m2\": " << num(r.floor_area_m2) << ", \"accessible_area_m2\": " << num(r.accessible_area_m2)
    << ", \"reachable_area_m2\": " << num(r.reachable_area_m2) << ", \"open_cells\": " << r.open_cells
    << ", \"landmarks\": " << (r.cost_map.nodes.empty() ? 0 : r.cost_map.nodes.size() - 1)
    << ", \"coverage_landmarks\": " << r.cost_map.coverage_landmarks << ", \"path\": [";
  for (size_t i = 0; i < r.path.size(); ++i)
    s << (i ? ", " : "") << "{\"x\": " << num(r.path[i].x()) << ", \"y\": " << num(r.path[i].y())
      << ", \"scan\": " << (r.scan_at[i] ? "true" : "false") << "}";
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
  for (size_t i = 0; i < r.path.size(); ++i) s << r.path[i].x() << "," << r.path[i].y() << "," << (r.scan_at[i] ? 1 : 0) << "\n";
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
