// The pose graph's relaxation: a drifted square loop, a wrong loop edge, degenerate graphs.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>
#include <stdexcept>

#include "scanstop_slam/pose_graph.h"

namespace scanstop {
namespace slam {
namespace {

double deg(double d) { return d * M_PI / 180.0; }

/// 20 poses on a 4 x 4 m square (5 per side, 1 m apart), turning 90 deg at each corner, starting
/// off the origin with a heading that is not zero.
std::vector<Pose2D> squareLoop() {
  std::vector<Pose2D> truth;
  Pose2D p(1.0, -2.0, deg(30));
  for (int i = 0; i < 20; ++i) {
    truth.push_back(p);
    p = p * Pose2D(1.0, 0.0, (i % 5 == 4) ? deg(90) : 0.0);
  }
  return truth;
}

Eigen::Matrix3d information(double sigma_m, double sigma_rad) {
  return Eigen::Vector3d(1 / (sigma_m * sigma_m), 1 / (sigma_m * sigma_m), 1 / (sigma_rad * sigma_rad)).asDiagonal();
}

/// The graph of the loop: exact consecutive edges, one exact loop edge 19 -> 0 (robust), initial
/// poses from odometry composed with a bias (each step 4 % long, 1.5 deg of yaw added).
PoseGraph driftedLoop(const std::vector<Pose2D>& truth) {
  PoseGraph g;
  Pose2D odom = truth[0];
  for (size_t i = 0; i < truth.size(); ++i) {
    if (i > 0) {
      const Pose2D step = truth[i - 1].between(truth[i]);
      odom = odom * Pose2D(step.x * 1.04, step.y * 1.04 + 0.01, step.yaw + deg(1.5));
    }
    g.addNode(odom);
  }
  for (size_t i = 1; i < truth.size(); ++i) {
    PoseGraphEdge e;
    e.from = i - 1;
    e.to = i;
    e.T_from_to = truth[i - 1].between(truth[i]);
    e.information = information(0.01, deg(0.5));
    g.addEdge(e);
  }
  PoseGraphEdge loop;
  loop.from = truth.size() - 1;
  loop.to = 0;
  loop.T_from_to = truth.back().between(truth[0]);
  loop.information = information(0.01, deg(0.5));
  loop.robust = true;
  g.addEdge(loop);
  return g;
}

double posErr(const Pose2D& a, const Pose2D& b) { return std::hypot(a.x - b.x, a.y - b.y); }
double yawErr(const Pose2D& a, const Pose2D& b) { return std::abs(normalizeAngle(a.yaw - b.yaw)); }

TEST(PoseGraph, RelaxesADriftedSquareLoopOntoTheTruth) {
  const std::vector<Pose2D> truth = squareLoop();
  PoseGraph g = driftedLoop(truth);
  // The drift is real: the last pose is far off before the relaxation.
  EXPECT_GT(posErr(g.poses().back(), truth.back()), 0.5);
  EXPECT_GT(yawErr(g.poses().back(), truth.back()), deg(20));
  for (const std::string loss : {"cauchy", "huber", "none"}) {
    PoseGraph h = g;
    PoseGraphConfig config;
    config.loss = loss;
    const PoseGraphSummary s = h.optimize(config);
    ASSERT_TRUE(s.solved) << loss << ": " << s.message;
    std::cout << loss << ": " << s.iterations << " iterations, cost " << s.initial_cost << " -> " << s.final_cost
              << ", largest move " << s.max_moved_m << " m\n";
    EXPECT_EQ(s.moved, truth.size() - 1) << loss;  // all but the fixed first node
    EXPECT_GT(s.max_moved_m, 0.5) << loss;
    EXPECT_LT(s.final_cost, 1e-12) << loss;
    EXPECT_GT(s.initial_cost, 1.0) << loss;
    for (size_t i = 0; i < truth.size(); ++i) {
      EXPECT_LT(posErr(h.poses()[i], truth[i]), 0.001) << loss << " node " << i;
      EXPECT_LT(yawErr(h.poses()[i], truth[i]), deg(0.01)) << loss << " node " << i;
      EXPECT_LE(std::abs(h.poses()[i].yaw), M_PI) << loss << " node " << i;
    }
    EXPECT_EQ(h.poses()[0].x, g.poses()[0].x);  // the gauge stays exactly
    EXPECT_EQ(h.poses()[0].yaw, g.poses()[0].yaw);
  }
}

TEST(PoseGraph, YawErrorsAreNormalizedAcrossPi) {
  // Two nodes around yaw = pi: the measurement says +179 deg -> -179 deg is a 2 deg turn, not -358.
  PoseGraph g;
  g.addNode(Pose2D(0, 0, deg(179)));
  g.addNode(Pose2D(0.5, 0.1, deg(170)));
  PoseGraphEdge e;
  e.from = 0;
  e.to = 1;
  e.T_from_to = Pose2D(1.0, 0.0, deg(2));
  e.information = information(0.01, deg(0.5));
  g.addEdge(e);
  const PoseGraphSummary s = g.optimize();
  ASSERT_TRUE(s.solved) << s.message;
  const Pose2D expected = Pose2D(0, 0, deg(179)) * e.T_from_to;
  EXPECT_LT(posErr(g.poses()[1], expected), 1e-6);
  EXPECT_LT(yawErr(g.poses()[1], expected), 1e-6);
  EXPECT_NEAR(g.poses()[1].yaw, deg(-179), 1e-6);
}

/// The loop with noisy edges (1 cm, 0.2 deg) and a wrong loop edge 10 -> 0 that claims node 10 is
/// 3 m and 40 deg away from where it is. With the robust loss the graph barely moves from the
/// relaxation without that edge; without it the wrong edge drags the loop by decimetres.
TEST(PoseGraph, ARobustLossKeepsAWrongLoopEdgeFromPullingTheGraph) {
  const std::vector<Pose2D> truth = squareLoop();
  std::mt19937 rng(4);
  std::normal_distribution<double> n_m(0.0, 0.01), n_rad(0.0, deg(0.2));
  PoseGraph clean;
  for (const Pose2D& p : truth) clean.addNode(p);
  const auto noisy = [&](size_t i, size_t j, bool robust) {
    PoseGraphEdge e;
    e.from = i;
    e.to = j;
    e.T_from_to = truth[i].between(truth[j]) * Pose2D(n_m(rng), n_m(rng), n_rad(rng));
    e.information = information(0.01, deg(0.2));
    e.robust = robust;
    return e;
  };
  for (size_t i = 1; i < truth.size(); ++i) clean.addEdge(noisy(i - 1, i, false));
  clean.addEdge(noisy(truth.size() - 1, 0, true));
  clean.addEdge(noisy(15, 0, true));
  PoseGraph with_outlier = clean;
  PoseGraphEdge wrong;
  wrong.from = 10;
  wrong.to = 0;
  wrong.T_from_to = truth[10].between(truth[0]) * Pose2D(3.0, -1.0, deg(40));
  wrong.information = information(0.01, deg(0.2));
  wrong.robust = true;
  with_outlier.addEdge(wrong);
  PoseGraph plain = with_outlier;

  ASSERT_TRUE(clean.optimize().solved);
  ASSERT_TRUE(with_outlier.optimize().solved);
  PoseGraphConfig least_squares;
  least_squares.loss = "none";
  ASSERT_TRUE(plain.optimize(least_squares).solved);
  double robust_max = 0.0, plain_max = 0.0, clean_max = 0.0;
  for (size_t i = 0; i < truth.size(); ++i) {
    robust_max = std::max(robust_max, posErr(with_outlier.poses()[i], clean.poses()[i]));
    plain_max = std::max(plain_max, posErr(plain.poses()[i], clean.poses()[i]));
    clean_max = std::max(clean_max, posErr(clean.poses()[i], truth[i]));
  }
  std::cout << "largest pose change by the wrong edge: robust " << robust_max * 1000 << " mm, least squares "
            << plain_max * 1000 << " mm; noisy loop vs truth " << clean_max * 1000 << " mm\n";
  EXPECT_LT(clean_max, 0.1);     // the noisy loop itself is fine
  EXPECT_LT(robust_max, 0.005);  // the wrong edge moves no pose by more than 5 mm
  EXPECT_GT(plain_max, 0.3);     // without the robust loss it drags the loop far
}

TEST(PoseGraph, EmptyAndOneNodeGraphsAreNothingToDo) {
  PoseGraph empty;
  PoseGraphSummary s = empty.optimize();
  EXPECT_TRUE(s.solved);
  EXPECT_EQ(s.moved, 0u);
  EXPECT_EQ(empty.size(), 0u);
  PoseGraph one;
  one.addNode(Pose2D(1, 2, 3));
  s = one.optimize();
  EXPECT_TRUE(s.solved);
  EXPECT_EQ(s.moved, 0u);
  EXPECT_EQ(one.poses()[0].x, 1.0);
  EXPECT_EQ(one.poses()[0].yaw, 3.0);
  // Two nodes without an edge: nothing moves either.
  one.addNode(Pose2D(5, 5, 0));
  s = one.optimize();
  EXPECT_TRUE(s.solved);
  EXPECT_EQ(s.moved, 0u);
}

TEST(PoseGraph, AComponentNotJoinedToTheFirstNodeKeepsItsOwnAnchor) {
  // Nodes 0-1 and 2-3 are joined among themselves only: each pair relaxes, its lowest node stays.
  PoseGraph g;
  g.addNode(Pose2D(0, 0, 0));
  g.addNode(Pose2D(1.2, 0.1, 0.05));
  g.addNode(Pose2D(10, 0, 0.3));
  g.addNode(Pose2D(10.5, 0.5, 0.2));
  PoseGraphEdge e;
  e.information = information(0.01, deg(0.5));
  e.from = 0;
  e.to = 1;
  e.T_from_to = Pose2D(1, 0, 0);
  g.addEdge(e);
  e.from = 2;
  e.to = 3;
  g.addEdge(e);
  const PoseGraphSummary s = g.optimize();
  ASSERT_TRUE(s.solved) << s.message;
  EXPECT_LT(posErr(g.poses()[1], Pose2D(1, 0, 0)), 1e-6);
  EXPECT_EQ(g.poses()[2].x, 10.0);
  EXPECT_EQ(g.poses()[2].yaw, 0.3);
  EXPECT_LT(posErr(g.poses()[3], Pose2D(10, 0, 0.3) * Pose2D(1, 0, 0)), 1e-6);
}

TEST(PoseGraph, BadEdgesAndConfigsAreRefused) {
  PoseGraph g;
  g.addNode(Pose2D());
  g.addNode(Pose2D(1, 0, 0));
  PoseGraphEdge e;
  e.from = 0;
  e.to = 2;
  EXPECT_THROW(g.addEdge(e), std::invalid_argument);  // unknown node
  e.to = 0;
  EXPECT_THROW(g.addEdge(e), std::invalid_argument);  // to itself
  e.to = 1;
  e.information = Eigen::Matrix3d::Zero();
  EXPECT_THROW(g.addEdge(e), std::invalid_argument);  // not positive definite
  e.information = Eigen::Matrix3d::Identity();
  e.information(0, 1) = 0.5;
  EXPECT_THROW(g.addEdge(e), std::invalid_argument);  // not symmetric
  e.information = Eigen::Matrix3d::Identity();
  e.T_from_to.x = NAN;
  EXPECT_THROW(g.addEdge(e), std::invalid_argument);
  EXPECT_EQ(g.edges().size(), 0u);
  EXPECT_THROW(g.addNode(Pose2D(INFINITY, 0, 0)), std::invalid_argument);
  PoseGraphConfig c;
  c.loss = "tukey";
  EXPECT_ANY_THROW(g.optimize(c));
  c = PoseGraphConfig();
  c.loss_scale = 0.0;
  EXPECT_ANY_THROW(g.optimize(c));
}

}  // namespace
}  // namespace slam
}  // namespace scanstop
