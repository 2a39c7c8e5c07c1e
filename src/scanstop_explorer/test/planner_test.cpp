#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <tuple>

#include "scanstop_common/error.h"
#include "scanstop_explorer/distance_transform.h"
#include "scanstop_explorer/planner.h"
#include "scanstop_explorer/skeleton.h"
#include "scenes.h"

using namespace scanstop::explorer;
using scanstop::Pose2D;

namespace {
PlanInput inputFor(const test::Scene& s, const cv::Mat& states, const std::vector<Eigen::Vector2d>& scans,
                   const Pose2D& robot) {
  PlanInput in;
  in.states = states;
  in.geometry = s.geometry;
  in.scan_positions = scans;
  in.robot = robot;
  return in;
}

/// Checks every planned path property the issue asks for.
void expectValidPath(const PlanResult& r, const PlannerConfig& cfg, const std::string& what) {
  ASSERT_TRUE(r.success) << what << ": " << r.message;
  ASSERT_FALSE(r.complete) << what;
  ASSERT_GE(r.path.size(), 2u) << what;
  ASSERT_EQ(r.path.size(), r.scan_at.size()) << what;
  EXPECT_TRUE(test::polylineOnAccessible(r.geometry, r.accessible, r.path, r.robot_snapped ? 1 : 0)) << what;
  for (size_t i = 1; i < r.path.size(); ++i) EXPECT_LE((r.path[i] - r.path[i - 1]).norm(), cfg.d_max_m + 1e-6) << what;
  EXPECT_FALSE(r.scan_at.front()) << what;
  EXPECT_TRUE(r.scan_at.back()) << what;
  EXPECT_NEAR((r.path.back() - r.target).norm(), 0.0, 1e-9) << what;
  // The target is the argmax of b = 1/(k+k0) * 1/(c+c0) over the reached cells lacking knowledge
  // or open (next to an occluded frontier) (computed here from the cost and knowledge maps).
  double best = 0.0;
  for (int row = 0; row < r.accessible.rows; ++row)
    for (int col = 0; col < r.accessible.cols; ++col) {
      const float c = r.cost_map.cost.at<float>(row, col);
      const bool candidate = r.knowledge.at<float>(row, col) < cfg.knowledge_threshold || r.open.at<uint8_t>(row, col);
      if (!std::isfinite(c) || !candidate) continue;
      best = std::max(best, 1.0 / (r.knowledge.at<float>(row, col) + cfg.k0) / (c * r.geometry.resolution + cfg.c0));
    }
  EXPECT_NEAR(r.score, best, 1e-6) << what;
  // Path length equals the cost of the target.
  double len = 0.0;
  for (size_t i = 1 + (r.robot_snapped ? 1 : 0); i < r.path.size(); ++i) len += (r.path[i] - r.path[i - 1]).norm();
  EXPECT_NEAR(len, r.target_cost_m, 1e-3) << what;
  // Each leg's clearance: what legClearance gives, and at least the robot's radius less a cell (the
  // legs run on the accessible floor).
  ASSERT_EQ(r.clearance_m.size(), r.path.size()) << what;
  for (size_t i = 1 + (r.robot_snapped ? 1 : 0); i < r.path.size(); ++i) {
    EXPECT_DOUBLE_EQ(r.clearance_m[i], legClearance(r.sq_dt, r.geometry, r.path[i - 1], r.path[i])) << what;
    EXPECT_GE(r.clearance_m[i], cfg.robot_radius_m - r.geometry.resolution) << what << " leg " << i;
  }
}
}  // namespace

TEST(LegClearance, TheSmallestDistanceFromTheLegToWhatIsNotFloor) {
  // A corridor 1 m wide (y 0 .. 1) and 4 m long at 5 cm, walls (not floor) around it, a post at
  // x 2.0-2.05 m, y 0.8-1.0.
  GridGeometry g;
  g.origin_x = -0.05;
  g.origin_y = -0.05;
  g.resolution = 0.05;
  g.width = 82;
  g.height = 22;
  cv::Mat floor(g.height, g.width, CV_8U, cv::Scalar(0));
  floor(cv::Rect(1, 1, 80, 20)).setTo(1);
  floor(cv::Rect(41, 17, 1, 4)).setTo(0);
  const cv::Mat sq_dt = squaredDistanceTransform(floor);
  // Along the middle, away from the post and the end walls: half the width, within a cell.
  const double middle = legClearance(sq_dt, g, {1.0, 0.5}, {1.5, 0.5});
  EXPECT_GE(middle, 0.45);
  EXPECT_LE(middle, 0.5);
  // Past the post (its lower face at y 0.8): 0.3 m, within a cell.
  const double past = legClearance(sq_dt, g, {1.0, 0.5}, {3.5, 0.5});
  EXPECT_GE(past, 0.25);
  EXPECT_LE(past, 0.3);
  // Near a wall: the smaller distance; through the post or off the grid: 0.
  EXPECT_LE(legClearance(sq_dt, g, {1.0, 0.2}, {1.5, 0.2}), 0.2);
  EXPECT_LE(legClearance(sq_dt, g, {0.3, 0.5}, {1.5, 0.5}), 0.3);  // from the end wall at x 0
  EXPECT_DOUBLE_EQ(legClearance(sq_dt, g, {2.025, 0.5}, {2.025, 0.95}), 0.0);
  EXPECT_DOUBLE_EQ(legClearance(sq_dt, g, {3.0, 0.5}, {9.0, 0.5}), 0.0);
}

TEST(PlannerConfig, ValidatesRanges) {
  PlannerConfig c;
  EXPECT_NO_THROW(c.validate());
  c.d_max_m = -1.0;
  try {
    c.validate();
    FAIL() << "no ConfigError";
  } catch (const scanstop::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("d_max_m"), std::string::npos);
  }
}

TEST(Accessible, ErodesByTheRobotRadius) {
  const test::Scene s = test::corridor();  // 1.2 m wide: accessible band 0.6 m wide
  const cv::Mat acc = accessibleFloor(squaredDistanceTransform(floorMask(test::idealStates(s))), 0.3 / 0.05);
  const cv::Point mid = s.geometry.cellOf(3.0, 0.6);
  EXPECT_TRUE(acc.at<uint8_t>(mid));
  EXPECT_FALSE(acc.at<uint8_t>(s.geometry.cellOf(3.0, 0.2)));  // 0.2 m from the wall
  EXPECT_TRUE(acc.at<uint8_t>(s.geometry.cellOf(3.0, 0.36)));  // 0.35 m from the wall cells' centres
  EXPECT_FALSE(acc.at<uint8_t>(s.geometry.cellOf(0.1, 0.6)));  // near the corridor's end
}

TEST(SegmentClear, ExactTraversal) {
  cv::Mat acc = cv::Mat::ones(10, 10, CV_8U);
  acc.at<uint8_t>(5, 5) = 0;
  EXPECT_TRUE(segmentClear(acc, cv::Point(0, 0), cv::Point(9, 0)));
  EXPECT_FALSE(segmentClear(acc, cv::Point(0, 5), cv::Point(9, 5)));
  EXPECT_FALSE(segmentClear(acc, cv::Point(2, 2), cv::Point(8, 8)));  // the diagonal through (5, 5)
  EXPECT_TRUE(segmentClear(acc, cv::Point(1, 3), cv::Point(6, 8)));   // parallel diagonal
  // A diagonal through a cell corner needs both cells beside it.
  cv::Mat checker = cv::Mat::ones(4, 4, CV_8U);
  checker.at<uint8_t>(1, 2) = 0;
  EXPECT_FALSE(segmentClear(checker, cv::Point(1, 1), cv::Point(2, 2)));
  EXPECT_TRUE(segmentClear(checker, cv::Point(0, 1), cv::Point(0, 3)));
  EXPECT_FALSE(segmentClear(checker, cv::Point(-1, 0), cv::Point(2, 0)));  // starts outside
}

TEST(Landmarks, ExtraPointsMakeSkeletonNeighboursVisibleAndShort) {
  const test::Scene s = test::lShape();
  const cv::Mat sq = squaredDistanceTransform(floorMask(test::idealStates(s)));
  const cv::Mat acc = accessibleFloor(sq, 6.0);
  const cv::Mat anchors = findAnchors(sq, acc);
  const cv::Mat skel = vincentSkeleton(acc, anchors);
  const std::vector<Landmark> lm = selectLandmarks(acc, sq, anchors, skel, 40.0);
  ASSERT_GE(lm.size(), 2u);
  for (const Landmark& l : lm) EXPECT_TRUE(acc.at<uint8_t>(l.cell));
  // The landmark graph alone connects all landmarks (one component) in an L of 5 m arms.
  const Graph g = reachabilityGraph(lm, acc, 40.0);
  std::vector<double> dist;
  std::vector<int> pred;
  dijkstra(g, {{0, 0.0}}, dist, pred);
  for (size_t i = 0; i < lm.size(); ++i) EXPECT_TRUE(std::isfinite(dist[i])) << "landmark " << i;
  for (size_t i = 0; i < g.adjacency.size(); ++i)
    for (const auto& [j, len] : g.adjacency[i]) {
      EXPECT_LE(len, 40.0);
      EXPECT_TRUE(segmentClear(acc, lm[i].pos, lm[j].pos));
    }
}

TEST(KnowledgeMap, CountsScansWithinRadius) {
  GridGeometry g;
  g.width = 100;
  g.height = 60;
  const cv::Mat k = knowledgeMap(g, {{1.0, 1.0}, {1.5, 1.0}, {4.0, 2.0}}, 1.0);
  EXPECT_FLOAT_EQ(k.at<float>(g.cellOf(1.25, 1.0)), 2.0f);
  EXPECT_FLOAT_EQ(k.at<float>(g.cellOf(0.3, 1.0)), 1.0f);
  EXPECT_FLOAT_EQ(k.at<float>(g.cellOf(4.0, 2.9)), 1.0f);
  EXPECT_FLOAT_EQ(k.at<float>(g.cellOf(3.0, 0.2)), 0.0f);
}

TEST(CostMap, DirectCellsCostTheirDistanceAndNothingIsCheaper) {
  const test::Scene s = test::twoRooms();
  const cv::Mat sq = squaredDistanceTransform(floorMask(test::idealStates(s)));
  const cv::Mat acc = accessibleFloor(sq, 6.0);
  const cv::Mat anchors = findAnchors(sq, acc);
  const cv::Mat skel = vincentSkeleton(acc, anchors);
  const std::vector<Landmark> lm = selectLandmarks(acc, sq, anchors, skel, 40.0);
  const Eigen::Vector2d robot = s.geometry.toGrid({1.0, 1.0});
  const CostMap cm = computeCostMap(acc, lm, robot, 40.0, 1000);
  int reached = 0;
  for (int r = 0; r < acc.rows; ++r)
    for (int c = 0; c < acc.cols; ++c) {
      const float cost = cm.cost.at<float>(r, c);
      if (!acc.at<uint8_t>(r, c)) {
        EXPECT_FALSE(std::isfinite(cost));
        continue;
      }
      ASSERT_TRUE(std::isfinite(cost)) << "accessible cell (" << c << ", " << r << ") of the connected floor unreached";
      ++reached;
      const Eigen::Vector2d cell(c + 0.5, r + 0.5);
      const double direct = (cell - robot).norm();
      EXPECT_GE(cost, direct - 1e-3);
      if (direct <= 40.0 && segmentClear(acc, robot, cell)) {
        EXPECT_NEAR(cost, direct, 1e-3);
      }
      // The predecessor sees the cell within d_max.
      const Landmark& p = cm.nodes[cm.predecessor.at<int>(r, c)];
      EXPECT_LE((p.pos - cell).norm(), 40.0 + 1e-9);
    }
  EXPECT_EQ(reached, cv::countNonZero(acc));
  // Room B is only reachable through the door: costs there exceed the straight-line distance.
  const cv::Point b = s.geometry.cellOf(7.0, 1.0);
  EXPECT_GT(cm.cost.at<float>(b), (Eigen::Vector2d(b.x + 0.5, b.y + 0.5) - robot).norm() + 5.0);
}

TEST(Plan, CorridorTwoRoomsLShapeTableDonut) {
  PlannerConfig cfg;
  struct Case {
    const char* name;
    test::Scene scene;
    Eigen::Vector2d robot;
  };
  for (const Case& c : {Case{"corridor", test::corridor(), {0.5, 0.6}}, Case{"two rooms", test::twoRooms(), {1.0, 1.0}},
                        Case{"L", test::lShape(), {4.4, 0.75}}, Case{"table", test::tableRoom(), {0.6, 0.6}},
                        Case{"donut", test::donut(), {3.0, 0.6}}}) {
    const cv::Mat states = test::seenStates(c.scene, {c.robot}, 2.5);
    const PlanInput in = inputFor(c.scene, states, {c.robot}, Pose2D(c.robot.x(), c.robot.y(), 0.0));
    const PlanResult r = planStep(in, cfg);
    expectValidPath(r, cfg, c.name);
    // With one scan the target leaves the scanned disc.
    EXPECT_GT((r.target - c.robot).norm(), cfg.k_r_m - 0.1) << c.name;
  }
}

TEST(Plan, DonutFarSideIsReachedAroundTheHole) {
  // Scan knowledge everywhere except the far side of the ring: the plan must go around.
  PlannerConfig cfg;
  const test::Scene s = test::donut();
  std::vector<Eigen::Vector2d> scans;
  for (int a = -8; a <= 8; ++a) {
    const double ang = -M_PI / 2 + a * M_PI / 12;
    scans.emplace_back(3.0 + 2.4 * std::cos(ang), 3.0 + 2.4 * std::sin(ang));
  }
  // The whole floor is known but a 1 m gap at the top of the outer wall is unknown (a frontier).
  cv::Mat states = test::idealStates(s);
  for (int r = 0; r < states.rows; ++r)
    for (int c = 0; c < states.cols; ++c) {
      const Eigen::Vector2d p = s.geometry.center({c, r});
      if (states.at<uint8_t>(r, c) == kObstacle && p.y() > 5.0 && std::abs(p.x() - 3.0) < 0.5)
        states.at<uint8_t>(r, c) = kUnknown;
    }
  const PlanResult r = planStep(inputFor(s, states, scans, Pose2D(3.0, 0.6, 0.0)), cfg);
  expectValidPath(r, cfg, "donut");
  // Every accessible cell of the ring is reached, also those no anchor sees.
  EXPECT_EQ(cv::countNonZero(r.cost_map.predecessor >= 0), cv::countNonZero(r.accessible));
  EXPECT_GT(r.target.y(), 4.5);  // the unscanned top of the ring
  EXPECT_GE(r.path.size(), 4u);  // around the hole in several legs
}

TEST(Plan, RobotOffTheAccessibleFloorIsJoinedOrRejected) {
  PlannerConfig cfg;
  const test::Scene s = test::corridor();
  const cv::Mat states = test::seenStates(s, {{0.5, 0.6}}, 2.5);
  const PlanResult near = planStep(inputFor(s, states, {{0.5, 0.6}}, Pose2D(0.5, 0.1, 0.0)), cfg);
  ASSERT_TRUE(near.success) << near.message;
  EXPECT_TRUE(near.robot_snapped);
  expectValidPath(near, cfg, "snapped");
  const PlanResult far = planStep(inputFor(s, states, {{0.5, 0.6}}, Pose2D(3.0, 5.0, 0.0)), cfg);
  EXPECT_FALSE(far.success);
  EXPECT_NE(far.message.find("start_snap_m"), std::string::npos) << far.message;
  PlanInput empty;
  EXPECT_FALSE(planStep(empty, cfg).success);
}

TEST(Plan, AGoalGivesThePathToTheNearestReachedCellAlsoWhenComplete) {
  // The whole two-room floor seen (no frontier: complete); the robot in the far room asks for the
  // way back to its start.
  PlannerConfig cfg;
  const test::Scene s = test::twoRooms();
  const cv::Mat states = test::idealStates(s);
  const Eigen::Vector2d start(1.0, 1.0);
  PlanInput in = inputFor(s, states, {start}, Pose2D(1.0, 1.0, 0.0));
  in.robot = Pose2D(7.0, 3.0, 0.0);  // far room, the door between them is at y in [1.5, 2.5]
  ASSERT_TRUE(planStep(in, cfg).complete);
  ASSERT_TRUE(planStep(in, cfg).path.empty());
  in.goal = start;
  const PlanResult back = planStep(in, cfg);
  ASSERT_TRUE(back.success) << back.message;
  EXPECT_TRUE(back.complete);
  EXPECT_FALSE(back.complete_reason.empty());
  ASSERT_GE(back.path.size(), 2u);
  EXPECT_TRUE(test::polylineOnAccessible(back.geometry, back.accessible, back.path, 0));
  for (size_t i = 1; i < back.path.size(); ++i) EXPECT_LE((back.path[i] - back.path[i - 1]).norm(), cfg.d_max_m + 1e-6);
  EXPECT_TRUE(back.scan_at.back());
  EXPECT_LT((back.target - start).norm(), s.geometry.resolution);  // the start is reached floor
  double len = 0.0;
  for (size_t i = 1; i < back.path.size(); ++i) len += (back.path[i] - back.path[i - 1]).norm();
  EXPECT_NEAR(len, back.target_cost_m, 1e-3);
  // A goal inside a wall or off the map: the nearest reached cell; one blacklisted: the next one.
  in.goal = Eigen::Vector2d(-50.0, 1.0);
  const PlanResult off = planStep(in, cfg);
  ASSERT_TRUE(off.success) << off.message;
  EXPECT_TRUE(std::isfinite(off.cost_map.cost.at<float>(off.target_cell)));
  in.blacklist.emplace_back(off.target, 0.3);
  const PlanResult next = planStep(in, cfg);
  ASSERT_TRUE(next.success) << next.message;
  EXPECT_GT((next.target - off.target).norm(), 0.3);
}

TEST(Termination, FiresOnAFullySeenRoomAndNotBefore) {
  PlannerConfig cfg;
  const test::Scene s = test::twoRooms();
  const double range = 3.0;
  std::vector<Eigen::Vector2d> scans{{1.0, 1.0}};
  Eigen::Vector2d robot = scans.back();
  bool complete = false;
  int steps = 0;
  for (; steps < 40 && !complete; ++steps) {
    const cv::Mat states = test::seenStates(s, scans, range);
    const PlanResult r = planStep(inputFor(s, states, scans, Pose2D(robot.x(), robot.y(), 0.0)), cfg);
    ASSERT_TRUE(r.success) << r.message;
    complete = r.complete;
    // Not before: while any free cell of the world is still unseen, the step is not complete.
    const int unseen = cv::countNonZero(s.free & (states != kFloor));
    if (complete) {
      EXPECT_EQ(unseen, 0) << "complete with " << unseen << " unseen cells after " << scans.size()
                           << " scans: " << r.complete_reason;
      EXPECT_EQ(r.open_cells, 0u);
      EXPECT_TRUE(r.path.empty());
      EXPECT_NE(r.complete_reason.find("knowledge_threshold"), std::string::npos);
    } else {
      EXPECT_GT(r.open_cells, 0u);
      expectValidPath(r, cfg, "step " + std::to_string(steps));
      robot = r.target;
      for (size_t i = 1; i < r.path.size(); ++i)  // the robot scans at every flagged waypoint
        if (r.scan_at[i]) scans.push_back(r.path[i]);
    }
  }
  EXPECT_TRUE(complete) << "not complete after " << steps << " steps";
  EXPECT_GT(scans.size(), 2u);  // it took several scans: the criterion did not fire early
}

TEST(Termination, FrontierAndOpenCells) {
  cv::Mat states = cv::Mat::zeros(5, 6, CV_8U);
  states(cv::Rect(0, 0, 3, 5)).setTo(kFloor);
  states.at<uint8_t>(0, 3) = kObstacle;
  const cv::Mat f = frontierCells(states);
  EXPECT_EQ(cv::countNonZero(f), 4);  // column 3 except the obstacle
  EXPECT_FALSE(f.at<uint8_t>(0, 3));
  cv::Mat cost(states.size(), CV_32F, cv::Scalar(std::numeric_limits<float>::infinity()));
  cost(cv::Rect(0, 0, 3, 5)).setTo(1.0f);
  cv::Mat k = cv::Mat::zeros(states.size(), CV_32F);
  // Column 2 borders the frontier, except beside the obstacle (sqrt(2) from the nearest frontier cell).
  EXPECT_EQ(cv::countNonZero(openCells(states, cost, k, cv::Mat(), 1.0, 1.0)), 4);
  EXPECT_EQ(cv::countNonZero(openCells(states, cost, k, cv::Mat(), 1.0, 3.0)), 14);  // all but (0, 0): sqrt(10)
  k.setTo(1.0f);
  EXPECT_EQ(cv::countNonZero(openCells(states, cost, k, cv::Mat(), 1.0, 3.0)), 0);
  EXPECT_EQ(cv::countNonZero(openCells(states, cost, k, cv::Mat(), 2.0, 3.0)), 14);  // the threshold is a parameter
}

TEST(Termination, FrontierIgnoresEnclosedPocketsAndWallBases) {
  // Open floor with an unknown 2 x 2 pocket (cells no point fell into).
  cv::Mat pocket(20, 20, CV_8U, cv::Scalar(kFloor));
  pocket(cv::Rect(5, 5, 2, 2)).setTo(kUnknown);
  EXPECT_EQ(cv::countNonZero(frontierCells(pocket)), 4);
  EXPECT_EQ(cv::countNonZero(frontierCells(pocket, 2.0)), 4);        // as large as the bound: kept
  EXPECT_EQ(cv::countNonZero(frontierCells(pocket, 3.0)), 0);        // smaller both ways: no frontier
  EXPECT_EQ(cv::countNonZero(frontierCells(pocket, 0.0, true)), 4);  // no obstacle near it
  // Floor in columns 0-9, a wall in column 10, unknown space behind it (columns 11-19). The wall has
  // a 5-cell opening in rows 5-9 and a floor cell in row 15 (a point at its base); both border the
  // unknown space.
  cv::Mat wall(20, 20, CV_8U, cv::Scalar(kUnknown));
  wall.colRange(0, 10).setTo(kFloor);
  wall.col(10).setTo(kObstacle);
  wall(cv::Rect(10, 5, 1, 5)).setTo(kFloor);
  wall.at<uint8_t>(15, 10) = kFloor;
  const cv::Mat plain = frontierCells(wall);
  EXPECT_EQ(cv::countNonZero(plain), 6);
  EXPECT_TRUE(plain.at<uint8_t>(15, 11));
  // Without wall bases: the opening's 3 middle cells (its end cells and the lone base cell lie
  // beside the wall's obstacle cells).
  const cv::Mat f = frontierCells(wall, 12.0, true);
  EXPECT_EQ(cv::countNonZero(f), 3);
  for (int r = 6; r <= 8; ++r) EXPECT_TRUE(f.at<uint8_t>(r, 11)) << r;
  EXPECT_FALSE(f.at<uint8_t>(15, 11));
}

TEST(TargetClearance, MovesToTheNearestAllowedCellFarEnoughFromAWall) {
  // 30 x 30 cells, a wall along column 0: sq_dt of (c, r) is c^2 (floor from column 1 on).
  cv::Mat sq_dt(30, 30, CV_32S);
  for (int r = 0; r < 30; ++r)
    for (int c = 0; c < 30; ++c) sq_dt.at<int>(r, c) = c * c;
  cv::Mat allowed = cv::Mat::ones(30, 30, CV_8U);
  EXPECT_EQ(clearTarget(sq_dt, allowed, {7, 12}, 10.0), cv::Point(10, 12));
  EXPECT_EQ(clearTarget(sq_dt, allowed, {12, 12}, 10.0), cv::Point(12, 12));  // far enough already
  EXPECT_EQ(clearTarget(sq_dt, allowed, {7, 12}, 0.0), cv::Point(7, 12));     // off
  allowed.at<uint8_t>(12, 10) = 0;  // not allowed (blacklisted or unreached): the next nearest, first in raster order
  EXPECT_EQ(clearTarget(sq_dt, allowed, {7, 12}, 10.0), cv::Point(10, 11));
  // The allowed cells that far from the wall are farther than the clearance from the target: it stays.
  cv::Mat far_only = cv::Mat::zeros(30, 30, CV_8U);
  far_only.colRange(18, 30).setTo(1);
  EXPECT_EQ(clearTarget(sq_dt, far_only, {7, 12}, 10.0), cv::Point(7, 12));
  EXPECT_EQ(clearTarget(sq_dt, far_only, {8, 12}, 10.0), cv::Point(18, 12));  // exactly the clearance away
  // A narrow passage (no cell has the clearance): it stays.
  EXPECT_EQ(clearTarget(cv::Mat(30, 30, CV_32S, cv::Scalar(16)), allowed, {7, 12}, 10.0), cv::Point(7, 12));
}

TEST(Plan, TargetClearanceKeepsTheTargetOffTheWalls) {
  PlannerConfig cfg;
  int moved = 0;
  for (const auto& [name, scene, robot] : {std::make_tuple("corridor", test::corridor(), Eigen::Vector2d(0.5, 0.6)),
                                           std::make_tuple("two rooms", test::twoRooms(), Eigen::Vector2d(1.0, 1.0)),
                                           std::make_tuple("L", test::lShape(), Eigen::Vector2d(4.4, 0.75))}) {
    const cv::Mat states = test::seenStates(scene, {robot}, 2.5);
    const PlanInput in = inputFor(scene, states, {robot}, Pose2D(robot.x(), robot.y(), 0.0));
    cfg.target_clearance_m = 0.0;
    const PlanResult plain = planStep(in, cfg);
    expectValidPath(plain, cfg, name);
    EXPECT_EQ(plain.target_moved_m, 0.0) << name;
    cfg.target_clearance_m = 0.5;
    const PlanResult r = planStep(in, cfg);
    expectValidPath(r, cfg, name);  // same argmax b, a path of the target's cost
    const double res = r.geometry.resolution;
    const double plain_clearance = std::sqrt(plain.sq_dt.at<int>(plain.target_cell)) * res;
    const double clearance = std::sqrt(r.sq_dt.at<int>(r.target_cell)) * res;
    EXPECT_NEAR(r.target_moved_m, (r.target - plain.target).norm(), 1e-9) << name;
    EXPECT_LE(r.target_moved_m, 0.5 + 1e-9) << name;
    if (plain_clearance >= 0.5) {
      EXPECT_EQ(r.target_cell, plain.target_cell) << name;
    } else if (r.target_moved_m > 0.0) {
      EXPECT_GE(clearance, 0.5 - 1e-9) << name;
    } else {
      // Stays only when no allowed cell within 0.5 m has the clearance (the corridor is 1.2 m wide).
      for (int row = 0; row < r.sq_dt.rows; ++row)
        for (int col = 0; col < r.sq_dt.cols; ++col)
          if (std::hypot(col - r.target_cell.x, row - r.target_cell.y) * res <= 0.5 &&
              r.cost_map.predecessor.at<int>(row, col) >= 0) {
            EXPECT_LT(std::sqrt(r.sq_dt.at<int>(row, col)) * res, 0.5) << name;
          }
    }
    std::printf("%s: argmax clearance %.2f m -> %.2f m (moved %.2f m)\n", name, plain_clearance, clearance,
                r.target_moved_m);
    moved += r.target_moved_m > 0.0;
  }
  EXPECT_GE(moved, 1);  // the argmax sits at the accessible border in these scenes
}
