#include "scanstop_explorer/planner.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <map>
#include <opencv2/imgproc.hpp>
#include <queue>
#include <sstream>
#include <stdexcept>

#include "scanstop_common/config.h"
#include "scanstop_common/error.h"
#include "scanstop_explorer/distance_transform.h"
#include "scanstop_explorer/floor_map.h"
#include "scanstop_explorer/skeleton.h"
#include "scanstop_explorer/visibility.h"

namespace scanstop {
namespace explorer {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
const cv::Point k4[4] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};

inline bool inside(const cv::Mat& m, const cv::Point& p) {
  return p.x >= 0 && p.y >= 0 && p.x < m.cols && p.y < m.rows;
}

std::string fmt(double v, int precision = 2) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(precision);
  s << v;
  return s.str();
}

class StageTimer {
 public:
  explicit StageTimer(std::vector<std::pair<std::string, double>>& out) : out_(out), t_(Clock::now()) {}
  void lap(const std::string& name) {
    const auto now = Clock::now();
    out_.emplace_back(name, std::chrono::duration<double, std::milli>(now - t_).count());
    t_ = now;
  }

 private:
  using Clock = std::chrono::steady_clock;
  std::vector<std::pair<std::string, double>>& out_;
  Clock::time_point t_;
};
}  // namespace

const char* landmarkKindName(Landmark::Kind kind) {
  switch (kind) {
    case Landmark::kRobot:
      return "robot";
    case Landmark::kAnchor:
      return "anchor";
    case Landmark::kSpecial:
      return "special";
    case Landmark::kExtra:
      return "extra";
    case Landmark::kCoverage:
      return "coverage";
  }
  return "?";
}

void PlannerConfig::validate() const {
  requireInRange("robot_radius_m", robot_radius_m, 1e-6, 5.0, "m");
  requireInRange("d_max_m", d_max_m, 1e-6, 50.0, "m");
  requireInRange("k_r_m", k_r_m, 1e-6, 50.0, "m");
  requireInRange("k0", k0, 1e-9, 1e6);
  requireInRange("c0", c0, 1e-9, 1e6, "m");
  requireInRange("knowledge_threshold", knowledge_threshold, 1e-9, 1e6);
  requireInRange("frontier_distance_m", frontier_distance_m, 1e-6, 50.0, "m");
  requireInRange("occluded_frontier_knowledge", occluded_frontier_knowledge, 0.0, 1e6);
  requireInRange("occluded_frontier_min_m", occluded_frontier_min_m, 0.0, 50.0, "m");
  requireInRange("frontier_min_unknown_m", frontier_min_unknown_m, 0.0, 50.0, "m");
  requireInRange("start_snap_m", start_snap_m, 0.0, 5.0, "m");
  requireInRange("target_clearance_m", target_clearance_m, 0.0, 5.0, "m");
  requireInRange("max_coverage_landmarks", max_coverage_landmarks, 0, 1e6);
  if (knowledge_model != "disc" && knowledge_model != "visibility")
    throw ConfigError("knowledge_model = '" + knowledge_model + "' is not one of: disc, visibility");
  if (target_score != "knowledge" && target_score != "gain")
    throw ConfigError("target_score = '" + target_score + "' is not one of: knowledge, gain");
  requireInRange("gain_sample_m", gain_sample_m, 1e-6, 5.0, "m");
  requireInRange("max_gain_samples", max_gain_samples, 1, 1e6);
  requireInRange("min_gain_m2", min_gain_m2, 0.0, 1e6, "m^2");
  if (gain_cells != "lacking" && gain_cells != "open")
    throw ConfigError("gain_cells = '" + gain_cells + "' is not one of: lacking, open");
  requireInRange("min_open_area_m2", min_open_area_m2, 0.0, 100.0, "m^2");
  requireInRange("beyond_reach_min_m2", beyond_reach_min_m2, 0.0, 1e4, "m^2");
  requireInRange("view_beyond_reach_m", view_beyond_reach_m, 1e-6, 10.0, "m");
  requireInRange("rescan_distance_m", rescan_distance_m, 0.0, 5.0, "m");
}

cv::Mat floorMask(const cv::Mat& states) { return (states == kFloor) / 255; }

cv::Mat accessibleFloor(const cv::Mat& sq_dt, double radius_cells) {
  const double r2 = radius_cells * radius_cells;
  cv::Mat out = cv::Mat::zeros(sq_dt.size(), CV_8U);
  for (int r = 0; r < sq_dt.rows; ++r) {
    const int* s = sq_dt.ptr<int>(r);
    uint8_t* o = out.ptr<uint8_t>(r);
    for (int c = 0; c < sq_dt.cols; ++c) o[c] = (s[c] > 0 && s[c] >= r2) ? 1 : 0;
  }
  return out;
}

bool segmentClear(const cv::Mat& accessible, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  auto ok = [&](int x, int y) {
    return x >= 0 && y >= 0 && x < accessible.cols && y < accessible.rows && accessible.at<uint8_t>(y, x);
  };
  int x = static_cast<int>(std::floor(a.x())), y = static_cast<int>(std::floor(a.y()));
  const int xe = static_cast<int>(std::floor(b.x())), ye = static_cast<int>(std::floor(b.y()));
  if (!ok(x, y)) return false;
  const Eigen::Vector2d d = b - a;
  const int sx = d.x() > 0 ? 1 : (d.x() < 0 ? -1 : 0), sy = d.y() > 0 ? 1 : (d.y() < 0 ? -1 : 0);
  double tmx = sx > 0 ? (x + 1 - a.x()) / d.x() : (sx < 0 ? (a.x() - x) / -d.x() : kInf);
  double tmy = sy > 0 ? (y + 1 - a.y()) / d.y() : (sy < 0 ? (a.y() - y) / -d.y() : kInf);
  const double tdx = sx ? 1.0 / std::abs(d.x()) : kInf, tdy = sy ? 1.0 / std::abs(d.y()) : kInf;
  int steps = std::abs(xe - x) + std::abs(ye - y) + 2;
  while ((x != xe || y != ye) && steps-- > 0) {
    if (std::min(tmx, tmy) > 1.0) break;
    if (std::abs(tmx - tmy) < 1e-9) {  // through a corner: both cells beside it must be free
      if (!ok(x + sx, y) || !ok(x, y + sy)) return false;
      x += sx;
      y += sy;
      tmx += tdx;
      tmy += tdy;
    } else if (tmx < tmy) {
      x += sx;
      tmx += tdx;
    } else {
      y += sy;
      tmy += tdy;
    }
    if (!ok(x, y)) return false;
  }
  return true;
}

bool segmentClear(const cv::Mat& accessible, const cv::Point& a, const cv::Point& b) {
  return segmentClear(accessible, Eigen::Vector2d(a.x + 0.5, a.y + 0.5), Eigen::Vector2d(b.x + 0.5, b.y + 0.5));
}

std::vector<Landmark> selectLandmarks(const cv::Mat& accessible, const cv::Mat& sq_dt, const cv::Mat& anchors,
                                      const cv::Mat& skeleton, double d_max_cells) {
  std::vector<Landmark> out;
  cv::Mat index(accessible.size(), CV_32S, cv::Scalar(-1));  // landmark index per pixel
  auto add = [&](const cv::Point& p, Landmark::Kind kind) {
    if (index.at<int>(p) >= 0) return;
    index.at<int>(p) = static_cast<int>(out.size());
    out.emplace_back(p, kind);
  };
  // One anchor per 8-connected anchor component: its pixel farthest from the boundary.
  cv::Mat labels;
  const int n = cv::connectedComponents(anchors, labels, 8, CV_32S);
  std::vector<cv::Point> best(n, cv::Point(-1, -1));
  for (int r = 0; r < labels.rows; ++r)
    for (int c = 0; c < labels.cols; ++c) {
      const int l = labels.at<int>(r, c);
      if (l <= 0) continue;
      if (best[l].x < 0 || sq_dt.at<int>(r, c) > sq_dt.at<int>(best[l])) best[l] = cv::Point(c, r);
    }
  for (int l = 1; l < n; ++l) add(best[l], Landmark::kAnchor);
  for (const cv::Point& p : specialPoints(skeleton)) add(p, Landmark::kSpecial);

  // Extra points: grow every landmark along the skeleton (4-neighbour BFS); where two regions
  // meet, the skeleton joins the two landmarks.
  cv::Mat owner(skeleton.size(), CV_32S, cv::Scalar(-1)), parent(skeleton.size(), CV_32S, cv::Scalar(-1));
  cv::Mat depth(skeleton.size(), CV_32S, cv::Scalar(0));
  std::deque<cv::Point> queue;
  for (size_t i = 0; i < out.size(); ++i)
    if (skeleton.at<uint8_t>(out[i].cell)) {
      owner.at<int>(out[i].cell) = static_cast<int>(i);
      queue.push_back(out[i].cell);
    }
  while (!queue.empty()) {
    const cv::Point p = queue.front();
    queue.pop_front();
    for (const cv::Point& d : k4) {
      const cv::Point q = p + d;
      if (!inside(skeleton, q) || !skeleton.at<uint8_t>(q) || owner.at<int>(q) >= 0) continue;
      owner.at<int>(q) = owner.at<int>(p);
      parent.at<int>(q) = p.y * skeleton.cols + p.x;
      depth.at<int>(q) = depth.at<int>(p) + 1;
      queue.push_back(q);
    }
  }
  std::map<std::pair<int, int>, std::pair<cv::Point, cv::Point>> meetings;
  for (int r = 0; r < skeleton.rows; ++r)
    for (int c = 0; c < skeleton.cols; ++c) {
      const int a = owner.at<int>(r, c);
      if (a < 0) continue;
      for (int k = 0; k < 2; ++k) {  // east and north neighbours: each pair once
        const cv::Point q(c + k4[k].x, r + k4[k].y);
        if (!inside(skeleton, q)) continue;
        const int b = owner.at<int>(q);
        if (b < 0 || b == a) continue;
        const auto key = std::make_pair(std::min(a, b), std::max(a, b));
        const cv::Point pa = a < b ? cv::Point(c, r) : q, pb = a < b ? q : cv::Point(c, r);
        auto it = meetings.find(key);
        if (it == meetings.end() ||
            depth.at<int>(pa) + depth.at<int>(pb) < depth.at<int>(it->second.first) + depth.at<int>(it->second.second))
          meetings[key] = {pa, pb};
      }
    }
  auto trace = [&](cv::Point p) {
    std::vector<cv::Point> chain{p};
    for (int i = parent.at<int>(p); i >= 0; i = parent.at<int>(chain.back()))
      chain.emplace_back(i % skeleton.cols, i / skeleton.cols);
    return chain;  // p ... landmark
  };
  const double d2max = d_max_cells * d_max_cells;
  for (const auto& m : meetings) {
    std::vector<cv::Point> path = trace(m.second.first);
    std::reverse(path.begin(), path.end());                      // landmark a ... meeting pixel
    const std::vector<cv::Point> tail = trace(m.second.second);  // meeting pixel ... landmark b
    path.insert(path.end(), tail.begin(), tail.end());
    std::vector<std::pair<size_t, size_t>> todo{{0, path.size() - 1}};
    while (!todo.empty()) {
      const auto [lo, hi] = todo.back();
      todo.pop_back();
      if (hi - lo < 2) continue;
      const cv::Point d = path[hi] - path[lo];
      if (d.dot(d) <= d2max && segmentClear(accessible, path[lo], path[hi])) continue;
      const size_t mid = (lo + hi) / 2;
      add(path[mid], Landmark::kExtra);
      todo.push_back({lo, mid});
      todo.push_back({mid, hi});
    }
  }
  return out;
}

size_t Graph::edgeCount() const {
  size_t n = 0;
  for (const auto& a : adjacency) n += a.size();
  return n / 2;
}

void addGraphNode(Graph& graph, const std::vector<Landmark>& nodes, int index, const cv::Mat& accessible,
                  double d_max_cells) {
  if (graph.adjacency.size() < nodes.size()) graph.adjacency.resize(nodes.size());
  for (int j = 0; j < static_cast<int>(nodes.size()); ++j) {
    if (j == index) continue;
    const double len = (nodes[j].pos - nodes[index].pos).norm();
    if (len > d_max_cells || !segmentClear(accessible, nodes[index].pos, nodes[j].pos)) continue;
    graph.adjacency[index].emplace_back(j, len);
    graph.adjacency[j].emplace_back(index, len);
  }
}

Graph reachabilityGraph(const std::vector<Landmark>& nodes, const cv::Mat& accessible, double d_max_cells) {
  Graph g;
  g.adjacency.resize(nodes.size());
  for (size_t i = 0; i < nodes.size(); ++i)
    for (size_t j = i + 1; j < nodes.size(); ++j) {
      const double len = (nodes[j].pos - nodes[i].pos).norm();
      if (len > d_max_cells || !segmentClear(accessible, nodes[i].pos, nodes[j].pos)) continue;
      g.adjacency[i].emplace_back(static_cast<int>(j), len);
      g.adjacency[j].emplace_back(static_cast<int>(i), len);
    }
  return g;
}

std::vector<int> dijkstra(const Graph& graph, const std::vector<std::pair<int, double>>& seeds,
                          std::vector<double>& dist, std::vector<int>& pred) {
  dist.resize(graph.adjacency.size(), kInf);
  pred.resize(graph.adjacency.size(), -1);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> pq;
  std::vector<int> improved;
  for (const auto& s : seeds) {
    if (s.second <= dist[s.first]) {
      dist[s.first] = s.second;
      pq.emplace(s.second, s.first);
      improved.push_back(s.first);
    }
  }
  while (!pq.empty()) {
    const auto [d, u] = pq.top();
    pq.pop();
    if (d > dist[u]) continue;
    for (const auto& [v, len] : graph.adjacency[u]) {
      if (d + len < dist[v]) {
        dist[v] = d + len;
        pred[v] = u;
        pq.emplace(dist[v], v);
        improved.push_back(v);
      }
    }
  }
  std::sort(improved.begin(), improved.end());
  improved.erase(std::unique(improved.begin(), improved.end()), improved.end());
  return improved;
}

namespace {
/// Gives every accessible cell within d_max that node n sees the cost dist(n) + |n - cell|.
void sweepNode(CostMap& cm, const cv::Mat& accessible, int n, double d_max_cells) {
  const double dn = cm.node_dist[n];
  if (!std::isfinite(dn)) return;
  const Eigen::Vector2d& p = cm.nodes[n].pos;
  const int r0 = std::max(0, static_cast<int>(std::floor(p.y() - d_max_cells)));
  const int r1 = std::min(accessible.rows - 1, static_cast<int>(std::ceil(p.y() + d_max_cells)));
  const int c0 = std::max(0, static_cast<int>(std::floor(p.x() - d_max_cells)));
  const int c1 = std::min(accessible.cols - 1, static_cast<int>(std::ceil(p.x() + d_max_cells)));
  const double d2max = d_max_cells * d_max_cells;
  for (int r = r0; r <= r1; ++r) {
    const uint8_t* acc = accessible.ptr<uint8_t>(r);
    float* cost = cm.cost.ptr<float>(r);
    int* pred = cm.predecessor.ptr<int>(r);
    const double dy = r + 0.5 - p.y();
    for (int c = c0; c <= c1; ++c) {
      if (!acc[c]) continue;
      const double dx = c + 0.5 - p.x();
      const double d2 = dx * dx + dy * dy;
      if (d2 > d2max) continue;
      const double cand = dn + std::sqrt(d2);
      if (cand >= cost[c]) continue;
      if (!segmentClear(accessible, p, Eigen::Vector2d(c + 0.5, r + 0.5))) continue;
      cost[c] = static_cast<float>(cand);
      pred[c] = n;
    }
  }
}
}  // namespace

CostMap computeCostMap(const cv::Mat& accessible, const std::vector<Landmark>& landmarks,
                       const Eigen::Vector2d& robot_pos, double d_max_cells, int max_coverage_landmarks) {
  CostMap cm;
  Landmark robot(cv::Point(static_cast<int>(std::floor(robot_pos.x())), static_cast<int>(std::floor(robot_pos.y()))),
                 Landmark::kRobot);
  robot.pos = robot_pos;
  if (!inside(accessible, robot.cell) || !accessible.at<uint8_t>(robot.cell))
    throw std::invalid_argument("computeCostMap: the robot is not on an accessible cell");
  cm.nodes.push_back(robot);
  cm.nodes.insert(cm.nodes.end(), landmarks.begin(), landmarks.end());
  cm.graph = reachabilityGraph(cm.nodes, accessible, d_max_cells);
  cm.node_dist.assign(cm.nodes.size(), kInf);
  cm.node_pred.assign(cm.nodes.size(), -1);
  dijkstra(cm.graph, {{0, 0.0}}, cm.node_dist, cm.node_pred);
  cm.cost = cv::Mat(accessible.size(), CV_32F, cv::Scalar(std::numeric_limits<float>::infinity()));
  cm.predecessor = cv::Mat(accessible.size(), CV_32S, cv::Scalar(-1));
  std::vector<int> order(cm.nodes.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return cm.node_dist[a] < cm.node_dist[b]; });
  for (int n : order) sweepNode(cm, accessible, n, d_max_cells);

  // Coverage landmarks: cells of the robot's component that no node sees (e.g. a donut).
  cv::Mat component = cv::Mat::zeros(accessible.rows + 2, accessible.cols + 2, CV_8U);
  cv::Mat acc_copy = accessible.clone();
  cv::floodFill(acc_copy, component, robot.cell, cv::Scalar(2), nullptr, cv::Scalar(0), cv::Scalar(0),
                4 | cv::FLOODFILL_MASK_ONLY | (1 << 8));
  component = component(cv::Rect(1, 1, accessible.cols, accessible.rows));
  std::vector<cv::Point> unreached;  // shrinks as coverage landmarks reach cells
  for (int r = 0; r < accessible.rows; ++r)
    for (int c = 0; c < accessible.cols; ++c)
      if (component.at<uint8_t>(r, c) && !std::isfinite(cm.cost.at<float>(r, c))) unreached.emplace_back(c, r);
  while (cm.coverage_landmarks < max_coverage_landmarks) {
    cv::Point best(-1, -1);
    float best_cost = std::numeric_limits<float>::infinity();
    size_t kept = 0;
    for (const cv::Point& p : unreached) {
      if (std::isfinite(cm.cost.at<float>(p))) continue;
      unreached[kept++] = p;
      for (const cv::Point& d : k4) {  // a reached 4-neighbour of an unreached component cell
        const cv::Point q = p + d;
        if (inside(accessible, q) && cm.cost.at<float>(q) < best_cost) {
          best_cost = cm.cost.at<float>(q);
          best = q;
        }
      }
    }
    unreached.resize(kept);
    if (best.x < 0) break;
    const int idx = static_cast<int>(cm.nodes.size());
    cm.nodes.emplace_back(best, Landmark::kCoverage);
    cm.node_dist.push_back(kInf);
    cm.node_pred.push_back(-1);
    addGraphNode(cm.graph, cm.nodes, idx, accessible, d_max_cells);
    // Its distance: via the node that sees the cell, or a shorter graph edge.
    double seed = best_cost;
    int seed_pred = cm.predecessor.at<int>(best);
    for (const auto& [v, len] : cm.graph.adjacency[idx])
      if (cm.node_dist[v] + len < seed) {
        seed = cm.node_dist[v] + len;
        seed_pred = v;
      }
    cm.node_pred[idx] = seed_pred;
    std::vector<int> improved = dijkstra(cm.graph, {{idx, seed}}, cm.node_dist, cm.node_pred);
    cm.node_pred[idx] = seed_pred;
    for (int n : improved) sweepNode(cm, accessible, n, d_max_cells);
    ++cm.coverage_landmarks;
  }
  return cm;
}

cv::Mat knowledgeMap(const GridGeometry& g, const std::vector<Eigen::Vector2d>& scan_positions, double k_r_m) {
  cv::Mat k = cv::Mat::zeros(g.height, g.width, CV_32F);
  for (const Eigen::Vector2d& s : scan_positions) {
    const cv::Point lo = g.cellOf(s.x() - k_r_m, s.y() - k_r_m), hi = g.cellOf(s.x() + k_r_m, s.y() + k_r_m);
    for (int r = std::max(0, lo.y); r <= std::min(g.height - 1, hi.y); ++r)
      for (int c = std::max(0, lo.x); c <= std::min(g.width - 1, hi.x); ++c)
        if ((g.center({c, r}) - s).squaredNorm() <= k_r_m * k_r_m) k.at<float>(r, c) += 1.0f;
  }
  return k;
}

cv::Mat evaluationMap(const cv::Mat& knowledge, const cv::Mat& cost_cells, double resolution, double k0, double c0,
                      const cv::Mat& blacklist) {
  cv::Mat b = cv::Mat::zeros(cost_cells.size(), CV_32F);
  for (int r = 0; r < b.rows; ++r)
    for (int c = 0; c < b.cols; ++c) {
      const float cost = cost_cells.at<float>(r, c);
      if (!std::isfinite(cost) || (!blacklist.empty() && blacklist.at<uint8_t>(r, c))) continue;
      b.at<float>(r, c) = static_cast<float>(1.0 / (knowledge.at<float>(r, c) + k0) * 1.0 / (cost * resolution + c0));
    }
  return b;
}

cv::Point argmaxCell(const cv::Mat& evaluation, const cv::Mat& candidates) {
  cv::Point best(-1, -1);
  float best_b = 0.0f;
  for (int r = 0; r < evaluation.rows; ++r)
    for (int c = 0; c < evaluation.cols; ++c)
      if (evaluation.at<float>(r, c) > best_b && (candidates.empty() || candidates.at<uint8_t>(r, c))) {
        best_b = evaluation.at<float>(r, c);
        best = cv::Point(c, r);
      }
  return best;
}

std::vector<std::pair<Eigen::Vector2d, int>> extractPath(const CostMap& cm, const cv::Point& target) {
  std::vector<std::pair<Eigen::Vector2d, int>> path;
  if (!inside(cm.predecessor, target) || cm.predecessor.at<int>(target) < 0) return path;
  path.emplace_back(Eigen::Vector2d(target.x + 0.5, target.y + 0.5), -1);
  for (int n = cm.predecessor.at<int>(target); n >= 0; n = cm.node_pred[n]) {
    path.emplace_back(cm.nodes[n].pos, n);
    if (path.size() > cm.nodes.size() + 1) throw std::logic_error("extractPath: predecessor cycle");
  }
  std::reverse(path.begin(), path.end());
  return path;
}

cv::Point clearTarget(const cv::Mat& sq_dt, const cv::Mat& allowed, const cv::Point& target, double clearance_cells) {
  if (clearance_cells <= 0.0 || !inside(sq_dt, target)) return target;
  const double need = clearance_cells * clearance_cells;
  if (sq_dt.at<int>(target) >= need) return target;
  const int reach = static_cast<int>(std::ceil(clearance_cells));
  cv::Point best = target;
  long best_d2 = std::numeric_limits<long>::max();
  for (int r = std::max(0, target.y - reach); r <= std::min(sq_dt.rows - 1, target.y + reach); ++r)
    for (int c = std::max(0, target.x - reach); c <= std::min(sq_dt.cols - 1, target.x + reach); ++c) {
      const long d2 =
          static_cast<long>(c - target.x) * (c - target.x) + static_cast<long>(r - target.y) * (r - target.y);
      if (d2 > need || d2 >= best_d2) continue;
      if (!allowed.at<uint8_t>(r, c) || sq_dt.at<int>(r, c) < need) continue;
      best_d2 = d2;
      best = cv::Point(c, r);
    }
  return best;
}

namespace {
/// Clears the cells of `cells` whose 8-connected region of `regions` (CV_8U, nonzero = in a region)
/// has a bounding box smaller than min_extent_cells in both directions.
void clearSmallRegions(cv::Mat& cells, const cv::Mat& regions, double min_extent_cells) {
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(regions, labels, stats, centroids, 8, CV_32S);
  std::vector<uint8_t> keep(n, 0);
  for (int l = 1; l < n; ++l)
    keep[l] = std::max(stats.at<int>(l, cv::CC_STAT_WIDTH), stats.at<int>(l, cv::CC_STAT_HEIGHT)) >= min_extent_cells;
  for (int r = 0; r < cells.rows; ++r)
    for (int c = 0; c < cells.cols; ++c)
      if (cells.at<uint8_t>(r, c) && !keep[labels.at<int>(r, c)]) cells.at<uint8_t>(r, c) = 0;
}
/// Clears the set cells of `cells` (CV_8U) in 8-connected pieces of fewer than min_cells cells;
/// returns how many it cleared.
size_t clearSmallAreas(cv::Mat& cells, double min_cells) {
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(cells != 0, labels, stats, centroids, 8, CV_32S);
  size_t cleared = 0;
  for (int r = 0; r < labels.rows; ++r)
    for (int c = 0; c < labels.cols; ++c) {
      const int l = labels.at<int>(r, c);
      if (l > 0 && l < n && stats.at<int>(l, cv::CC_STAT_AREA) < min_cells) {
        cells.at<uint8_t>(r, c) = 0;
        ++cleared;
      }
    }
  return cleared;
}
}  // namespace

cv::Mat frontierCells(const cv::Mat& states, double min_unknown_cells, bool ignore_wall_base) {
  // Floor cells that may border a frontier: all, or those with no obstacle among their 8 neighbours.
  cv::Mat source = states == kFloor;
  if (ignore_wall_base) {
    cv::Mat near_obstacle;
    cv::dilate(states == kObstacle, near_obstacle, cv::Mat::ones(3, 3, CV_8U), cv::Point(-1, -1), 1,
               cv::BORDER_CONSTANT, cv::Scalar(0));
    source &= ~near_obstacle;
  }
  cv::Mat f = cv::Mat::zeros(states.size(), CV_8U);
  for (int r = 0; r < states.rows; ++r)
    for (int c = 0; c < states.cols; ++c) {
      if (states.at<uint8_t>(r, c) != kUnknown) continue;
      for (const cv::Point& d : k4) {
        const cv::Point q(c + d.x, r + d.y);
        if (inside(states, q) && source.at<uint8_t>(q)) {
          f.at<uint8_t>(r, c) = 1;
          break;
        }
      }
    }
  // Enclosed unknown pockets (bounding box smaller than min_unknown_cells both ways) do not count.
  if (min_unknown_cells > 1.0) clearSmallRegions(f, states == kUnknown, min_unknown_cells);
  return f;
}

cv::Mat occludedFrontier(const cv::Mat& states, const GridGeometry& g, const std::vector<Eigen::Vector2d>& scans,
                         double view_radius_m, double min_extent_cells, const cv::Mat& given_frontier) {
  const cv::Mat frontier = given_frontier.empty() ? frontierCells(states) : given_frontier;
  cv::Mat occluded = frontier.clone();
  std::vector<cv::Point> scan_cells;
  for (const Eigen::Vector2d& s : scans) scan_cells.push_back(g.cellOf(s.x(), s.y()));
  const double r2 = view_radius_m * view_radius_m;
  // A line may run through this many unknown cells just before the frontier cell (a line at a
  // grazing angle to a straight frontier enters it early); before them it must cross floor cells
  // with no obstacle cell beside them (a line that grazes a door jamb does not count as a view).
  constexpr int kGrazeCells = 2;
  for (int r = 0; r < states.rows; ++r)
    for (int c = 0; c < states.cols; ++c) {
      if (!frontier.at<uint8_t>(r, c)) continue;
      const Eigen::Vector2d fc = g.center({c, r});
      for (size_t i = 0; i < scans.size(); ++i) {
        if ((scans[i] - fc).squaredNorm() > r2 || !inside(states, scan_cells[i])) continue;
        cv::LineIterator it(states, scan_cells[i], cv::Point(c, r), 4);
        bool clear = true;
        for (int k = 0; k + 1 < it.count && clear; ++k, ++it) {
          const uint8_t v = **it;
          if (k + 1 + kGrazeCells >= it.count) {
            clear = v != kObstacle;
          } else {  // a floor cell with no obstacle beside it (a line grazing a jamb is not clear)
            clear = v == kFloor;
            const cv::Point p = it.pos();
            for (int dy = -1; dy <= 1 && clear; ++dy)
              for (int dx = -1; dx <= 1 && clear; ++dx) {
                const cv::Point q(p.x + dx, p.y + dy);
                clear = !inside(states, q) || states.at<uint8_t>(q) != kObstacle;
              }
          }
        }
        if (clear) {
          occluded.at<uint8_t>(r, c) = 0;
          break;
        }
      }
    }
  // Short frontier pieces (8-connected pieces of the whole frontier, so that a shadow edge the
  // grid traversal calls partly seen stays one piece) do not count.
  if (min_extent_cells > 1.0) clearSmallRegions(occluded, frontier, min_extent_cells);
  return occluded;
}

cv::Mat openCells(const cv::Mat& states, const cv::Mat& cost_cells, const cv::Mat& knowledge, const cv::Mat& blacklist,
                  double knowledge_threshold, double frontier_distance_cells, const cv::Mat& occluded,
                  double occluded_knowledge, const cv::Mat& given_frontier) {
  const cv::Mat frontier = given_frontier.empty() ? frontierCells(states) : given_frontier;
  const cv::Mat sq = squaredDistanceTransform(1 - frontier);
  const bool use_occluded = !occluded.empty() && occluded_knowledge > knowledge_threshold;
  const cv::Mat sq_occ = use_occluded ? squaredDistanceTransform(1 - (occluded != 0) / 255) : cv::Mat();
  const double fd2 = frontier_distance_cells * frontier_distance_cells;
  cv::Mat open = cv::Mat::zeros(states.size(), CV_8U);
  for (int r = 0; r < states.rows; ++r)
    for (int c = 0; c < states.cols; ++c) {
      if (!std::isfinite(cost_cells.at<float>(r, c))) continue;
      if (!blacklist.empty() && blacklist.at<uint8_t>(r, c)) continue;
      const float k = knowledge.at<float>(r, c);
      const bool near_frontier = k < knowledge_threshold && sq.at<int>(r, c) <= fd2;
      const bool near_occluded = use_occluded && k < occluded_knowledge && sq_occ.at<int>(r, c) <= fd2;
      if (near_frontier || near_occluded) open.at<uint8_t>(r, c) = 1;
    }
  return open;
}

cv::Mat rasterizeDiscs(const GridGeometry& g, const std::vector<std::pair<Eigen::Vector2d, double>>& discs) {
  cv::Mat m = cv::Mat::zeros(g.height, g.width, CV_8U);
  for (const auto& [center, radius] : discs) {
    const cv::Point lo = g.cellOf(center.x() - radius, center.y() - radius);
    const cv::Point hi = g.cellOf(center.x() + radius, center.y() + radius);
    for (int r = std::max(0, lo.y); r <= std::min(g.height - 1, hi.y); ++r)
      for (int c = std::max(0, lo.x); c <= std::min(g.width - 1, hi.x); ++c)
        if ((g.center({c, r}) - center).norm() <= radius) m.at<uint8_t>(r, c) = 1;
  }
  return m;
}

PlanResult computeMaps(const PlanInput& in, const PlannerConfig& cfg) {
  PlanResult res;
  res.geometry = in.geometry;
  res.robot = in.robot;
  res.states = in.states;
  const GridGeometry& g = in.geometry;
  if (in.states.empty() || g.width == 0) {
    res.message = "no floor known yet: take and register a scan first";
    return res;
  }
  if (in.states.type() != CV_8U || in.states.cols != g.width || in.states.rows != g.height)
    throw std::invalid_argument("computeMaps: states must be CV_8U of the geometry's size");
  StageTimer timer(res.timings_ms);
  const double res_m = g.resolution;
  res.sq_dt = squaredDistanceTransform(floorMask(in.states));
  timer.lap("distance_transform");
  res.accessible = accessibleFloor(res.sq_dt, cfg.robot_radius_m / res_m);
  timer.lap("erosion");
  res.anchors = findAnchors(res.sq_dt, res.accessible);
  timer.lap("anchors");
  res.skeleton = vincentSkeleton(res.accessible, res.anchors, &res.skeleton_unpruned);
  timer.lap("skeleton");
  const double d_max_cells = cfg.d_max_m / res_m;
  const std::vector<Landmark> landmarks =
      selectLandmarks(res.accessible, res.sq_dt, res.anchors, res.skeleton, d_max_cells);
  timer.lap("landmarks");
  res.knowledge = cfg.knowledge_model == "visibility"
                      ? visibilityKnowledgeMap(in.states, g, in.scan_positions, cfg.k_r_m)
                      : knowledgeMap(g, in.scan_positions, cfg.k_r_m);
  timer.lap("knowledge");
  res.floor_area_m2 = cv::countNonZero(in.states == kFloor) * g.cellArea();
  res.accessible_area_m2 = cv::countNonZero(res.accessible) * g.cellArea();

  // The robot node: its cell, or the nearest accessible cell within start_snap_m.
  Eigen::Vector2d robot_pos = g.toGrid(Eigen::Vector2d(in.robot.x, in.robot.y));
  cv::Point rc(static_cast<int>(std::floor(robot_pos.x())), static_cast<int>(std::floor(robot_pos.y())));
  if (!inside(res.accessible, rc) || !res.accessible.at<uint8_t>(rc)) {
    const double snap = cfg.start_snap_m / res_m;
    double best = kInf;
    cv::Point best_cell(-1, -1);
    for (int r = static_cast<int>(std::floor(robot_pos.y() - snap));
         r <= static_cast<int>(std::ceil(robot_pos.y() + snap)); ++r)
      for (int c = static_cast<int>(std::floor(robot_pos.x() - snap));
           c <= static_cast<int>(std::ceil(robot_pos.x() + snap)); ++c) {
        if (!inside(res.accessible, {c, r}) || !res.accessible.at<uint8_t>(r, c)) continue;
        const double d = (Eigen::Vector2d(c + 0.5, r + 0.5) - robot_pos).norm();
        if (d <= snap && d < best) {
          best = d;
          best_cell = cv::Point(c, r);
        }
      }
    if (best_cell.x < 0) {
      res.message = "the robot at (" + fmt(in.robot.x) + ", " + fmt(in.robot.y) +
                    ") m is not on the accessible floor and no accessible cell is within start_snap_m = " +
                    fmt(cfg.start_snap_m) + " m";
      return res;
    }
    rc = best_cell;
    robot_pos = Eigen::Vector2d(rc.x + 0.5, rc.y + 0.5);
    res.robot_snapped = true;
  }
  res.robot_cell = rc;
  res.cost_map = computeCostMap(res.accessible, landmarks, robot_pos, d_max_cells, cfg.max_coverage_landmarks);
  timer.lap("graph_and_cost");
  res.reachable_area_m2 = cv::countNonZero(res.cost_map.predecessor >= 0) * g.cellArea();
  res.success = true;
  return res;
}

namespace {
/// The part of complete_reason that names unexplored floor cut off from the robot (PlanResult::cut_off_area_m2).
std::string cutOffText(double cut_off_m2) {
  if (cut_off_m2 < 0.5) return "";
  return "; " + fmt(cut_off_m2, 1) +
         " m^2 of accessible floor next to unexplored space is not connected to the robot in the floor map (a door "
         "the map shows too narrow for the robot, or closed by map error): it stays unexplored";
}

/// target_score "gain": the sampled candidate with the largest g / (c + c0) whose gain g reaches
/// min_gain_m2 (first in raster order on ties); sets target_cell, score and target_gain_m2, or
/// leaves target_cell at (-1, -1).
void chooseByGain(PlanResult& res, const cv::Mat& candidates, const PlannerConfig& cfg) {
  const GridGeometry& g = res.geometry;
  const int sample = std::max(1, static_cast<int>(std::lround(cfg.gain_sample_m / g.resolution)));
  if (cfg.gain_cells == "open") {
    const cv::Mat open = res.open != 0;
    res.gain = gainMap(res.states, g, (res.states == kUnknown) | open, open, candidates, cfg.k_r_m, sample,
                       cfg.max_gain_samples);
  } else {
    res.gain = gainMap(res.states, g, res.knowledge, cfg.knowledge_threshold, candidates, cfg.k_r_m, sample,
                       cfg.max_gain_samples);
  }
  double best = 0.0;
  for (int r = 0; r < res.gain.rows; ++r)
    for (int c = 0; c < res.gain.cols; ++c) {
      const double gain = res.gain.at<float>(r, c);
      if (gain <= 0.0 || gain < cfg.min_gain_m2) continue;
      const double b = gain / (res.cost_map.cost.at<float>(r, c) * g.resolution + cfg.c0);
      if (b > best) {
        best = b;
        res.target_cell = cv::Point(c, r);
        res.target_gain_m2 = gain;
      }
    }
  if (res.target_cell.x >= 0) res.score = best;
}
}  // namespace

void choosePlan(PlanResult& res, const PlanInput& in, const PlannerConfig& cfg) {
  if (res.cost_map.cost.empty()) return;  // computeMaps failed; its message stands
  StageTimer timer(res.timings_ms);
  const GridGeometry& g = res.geometry;
  const double res_m = g.resolution;
  res.blacklist = rasterizeDiscs(g, in.blacklist);
  res.evaluation = evaluationMap(res.knowledge, res.cost_map.cost, res_m, cfg.k0, cfg.c0, res.blacklist);
  const cv::Mat frontier = frontierCells(res.states, cfg.frontier_min_unknown_m / res_m, cfg.ignore_wall_base_frontier);
  if (cfg.occluded_frontier_knowledge > cfg.knowledge_threshold)
    res.occluded_frontier =
        occludedFrontier(res.states, g, in.scan_positions, cfg.k_r_m, cfg.occluded_frontier_min_m / res_m, frontier);
  res.open =
      openCells(res.states, res.cost_map.cost, res.knowledge, res.blacklist, cfg.knowledge_threshold,
                cfg.frontier_distance_m / res_m, res.occluded_frontier, cfg.occluded_frontier_knowledge, frontier);
  const cv::Mat reached = res.cost_map.predecessor >= 0;
  const double fd = cfg.frontier_distance_m / res_m;
  const cv::Mat near_frontier = squaredDistanceTransform(1 - frontier) <= fd * fd;
  res.cut_off_area_m2 =
      cv::countNonZero((res.accessible != 0) & ~reached & near_frontier & (res.knowledge < cfg.knowledge_threshold)) *
      g.cellArea();
  if (cfg.beyond_reach_min_m2 > 0.0 && cfg.occluded_frontier_knowledge > 0.0) {
    // Floor next to a frontier that no path reaches, in large pieces: the reached cells near it
    // stay open until their knowledge reaches occluded_frontier_knowledge.
    cv::Mat far_floor = (res.states == kFloor) & near_frontier & ~reached;
    clearSmallAreas(far_floor, cfg.beyond_reach_min_m2 / g.cellArea());
    if (cv::countNonZero(far_floor) > 0) {
      const double view = cfg.view_beyond_reach_m / res_m;
      const cv::Mat near_view = squaredDistanceTransform(1 - far_floor / 255) <= view * view;
      for (int r = 0; r < res.open.rows; ++r)
        for (int c = 0; c < res.open.cols; ++c) {
          if (res.open.at<uint8_t>(r, c) || !reached.at<uint8_t>(r, c) || !near_view.at<uint8_t>(r, c)) continue;
          if (!res.blacklist.empty() && res.blacklist.at<uint8_t>(r, c)) continue;
          if (res.knowledge.at<float>(r, c) >= cfg.occluded_frontier_knowledge) continue;
          res.open.at<uint8_t>(r, c) = 1;
          ++res.open_beyond_reach;
        }
    }
  }
  if (cfg.min_open_area_m2 > 0.0)  // small pieces of open cells are not open
    res.open_cells_ignored = clearSmallAreas(res.open, cfg.min_open_area_m2 / g.cellArea());
  timer.lap("evaluation_and_termination");
  res.open_cells = static_cast<size_t>(cv::countNonZero(res.open));
  const int n_reached = cv::countNonZero(reached);
  const int n_known = cv::countNonZero(reached & (res.knowledge >= cfg.knowledge_threshold));
  res.coverage = n_reached > 0 ? static_cast<double>(n_known) / n_reached : 0.0;
  const int n_black = cv::countNonZero(reached & (res.blacklist != 0));
  res.path.clear();
  res.scan_at.clear();
  res.target_cell = cv::Point(-1, -1);
  res.target = Eigen::Vector2d(in.robot.x, in.robot.y);
  res.score = 0.0;
  res.target_gain_m2 = -1.0;
  res.target_cost_m = 0.0;
  res.complete = res.open_cells == 0;
  if (res.complete) {
    res.complete_reason =
        "no reachable cell within frontier_distance_m = " + fmt(cfg.frontier_distance_m) +
        " m of unknown space has knowledge below knowledge_threshold = " + fmt(cfg.knowledge_threshold) +
        (res.occluded_frontier.empty()
             ? std::string()
             : " (below occluded_frontier_knowledge = " + fmt(cfg.occluded_frontier_knowledge) +
                   " next to a frontier no scan has in sight)") +
        " (" + std::to_string(n_reached) + " reachable cells, " + std::to_string(n_black) +
        " blacklisted as unreachable" +
        (res.open_cells_ignored > 0
             ? ", " + std::to_string(res.open_cells_ignored) +
                   " open cells in pieces under min_open_area_m2 = " + fmt(cfg.min_open_area_m2, 3) + " m^2 ignored"
             : std::string()) +
        ")" + cutOffText(res.cut_off_area_m2);
    res.message = "exploration complete";
    if (!in.goal) return;
  }
  cv::Mat target_cells = reached & (res.blacklist == 0);  // where a target (or its move off a wall) may lie
  if (in.goal) {
    // The reached, not blacklisted cell nearest to the goal (first in raster order on ties).
    const cv::Point goal_cell = g.cellOf(in.goal->x(), in.goal->y());
    double best = std::numeric_limits<double>::infinity();
    for (int r = 0; r < target_cells.rows; ++r)
      for (int c = 0; c < target_cells.cols; ++c) {
        if (!target_cells.at<uint8_t>(r, c)) continue;
        const double d2 = std::pow(c - goal_cell.x, 2) + std::pow(r - goal_cell.y, 2);
        if (d2 < best) {
          best = d2;
          res.target_cell = cv::Point(c, r);
        }
      }
    if (res.target_cell.x < 0) {
      res.success = false;
      res.message = "no reachable cell to go to near the goal (" + fmt(in.goal->x()) + ", " + fmt(in.goal->y()) + ")";
      return;
    }
  } else {
    cv::Mat candidates = (res.knowledge < cfg.knowledge_threshold) | (res.open != 0);
    if (cfg.rescan_distance_m > 0.0) {  // not where a scan was taken
      std::vector<std::pair<Eigen::Vector2d, double>> scanned;
      for (const Eigen::Vector2d& p : in.scan_positions) scanned.emplace_back(p, cfg.rescan_distance_m);
      const cv::Mat near_scan = rasterizeDiscs(g, scanned) != 0;
      candidates &= ~near_scan;
      target_cells &= ~near_scan;
    }
    if (cfg.target_score == "gain")
      chooseByGain(res, cfg.gain_cells == "open" ? target_cells : candidates & target_cells, cfg);
    if (res.target_cell.x < 0) res.target_cell = argmaxCell(res.evaluation, candidates);
    timer.lap(cfg.target_score == "gain" ? "target_by_gain" : "target");
  }
  if (res.target_cell.x < 0) {
    res.complete = true;
    res.complete_reason = "every reachable cell that lacks knowledge is blacklisted as unreachable" +
                          std::string(cfg.rescan_distance_m > 0.0 ? " or within rescan_distance_m of a scan" : "") +
                          " (" + std::to_string(res.open_cells) + " open cells left)" + cutOffText(res.cut_off_area_m2);
    res.message = "exploration complete";
    return;
  }
  if (!res.complete) res.complete_reason.clear();
  if (res.target_gain_m2 < 0.0) res.score = res.evaluation.at<float>(res.target_cell);
  {
    const cv::Point argmax = res.target_cell;
    res.target_cell = clearTarget(res.sq_dt, target_cells, argmax, cfg.target_clearance_m / res_m);
    res.target_moved_m = std::hypot(res.target_cell.x - argmax.x, res.target_cell.y - argmax.y) * res_m;
  }
  res.target_cost_m = res.cost_map.cost.at<float>(res.target_cell) * res_m;
  res.target = g.center(res.target_cell);
  const auto cells = extractPath(res.cost_map, res.target_cell);
  auto toMap = [&](const Eigen::Vector2d& p) {
    return Eigen::Vector2d(g.origin_x + p.x() * res_m, g.origin_y + p.y() * res_m);
  };
  if (res.robot_snapped) {  // leave the inaccessible spot first
    res.path.emplace_back(in.robot.x, in.robot.y);
    res.scan_at.push_back(false);
  }
  for (size_t i = 0; i < cells.size(); ++i) {
    res.path.push_back(i == 0 && !res.robot_snapped ? Eigen::Vector2d(in.robot.x, in.robot.y) : toMap(cells[i].first));
    res.scan_at.push_back(i > 0);  // every intermediate landmark and the target
  }
  for (size_t i = 0; i < res.path.size(); ++i)
    res.clearance_m.push_back(legClearance(res.sq_dt, g, res.path[i == 0 ? 0 : i - 1], res.path[i]));
  timer.lap("path");
  res.message =
      std::string(in.goal ? (res.complete ? "exploration complete; " : "") + std::string("to the goal: ") : "") +
      "target (" + fmt(res.target.x()) + ", " + fmt(res.target.y()) + ") m, " + std::to_string(res.path.size()) +
      " waypoints, " + fmt(res.target_cost_m) + " m, b = " + fmt(res.score, 4) +
      (res.target_gain_m2 >= 0.0 ? " (expected gain " + fmt(res.target_gain_m2, 1) + " m^2)" : std::string()) + ", " +
      std::to_string(res.open_cells) + " open cells" +
      (res.open_beyond_reach > 0 ? " (" + std::to_string(res.open_beyond_reach) + " near floor seen beyond reach)"
                                 : std::string()) +
      (res.target_moved_m > 0.0 ? " (moved " + fmt(res.target_moved_m) + " m off the wall)" : "");
}

double legClearance(const cv::Mat& sq_dt, const GridGeometry& geometry, const Eigen::Vector2d& a,
                    const Eigen::Vector2d& b) {
  const Eigen::Vector2d ga = geometry.toGrid(a), gb = geometry.toGrid(b);
  const int samples = 1 + static_cast<int>(std::ceil(2.0 * (gb - ga).norm()));  // every half cell
  double min_sq = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= samples; ++k) {
    const Eigen::Vector2d p = ga + (gb - ga) * (static_cast<double>(k) / samples);
    const int x = static_cast<int>(std::floor(p.x())), y = static_cast<int>(std::floor(p.y()));
    if (x < 0 || y < 0 || x >= sq_dt.cols || y >= sq_dt.rows) return 0.0;
    min_sq = std::min(min_sq, static_cast<double>(sq_dt.at<int>(y, x)));
  }
  // Less a cell: the surface may lie anywhere in its cell, and the leg anywhere in the cells it crosses.
  return std::max(0.0, (std::sqrt(min_sq) - 1.0) * geometry.resolution);
}

PlanResult planStep(const PlanInput& input, const PlannerConfig& config) {
  PlanResult r = computeMaps(input, config);
  choosePlan(r, input, config);
  return r;
}

}  // namespace explorer
}  // namespace scanstop
