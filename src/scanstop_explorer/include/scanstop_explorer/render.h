#pragma once
/// What users see of a planning step: PNG images like thesis figures 8.2-8.6, the plan as JSON and
/// CSV, and the grids as occupancy values (ROS-free; the node wraps them into messages).

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "scanstop_explorer/planner.h"

namespace scanstop {
namespace explorer {

/// Images of one step (BGR, north up, `scale` pixels per cell), in this order: "floor" (grey
/// floor, red obstacles, black unknown, orange: open cells that keep exploration going), "distance" (distance transform
/// of the accessible floor, skeleton in blue, anchors in yellow), "cost" (brighter = farther), "knowledge" (brighter =
/// more), "evaluation" (brighter = better; the target is the brightest cell). Each has the robot (green), the landmarks
/// (red), the path (cyan) and the target (magenta) drawn in. Below the map (rows scale * height and on) a white footer
/// holds a scale bar and the legend of the image's colours.
std::vector<std::pair<std::string, cv::Mat>> renderPlanImages(const PlanResult& result, int scale = 2);
/// Writes <dir>/<prefix><name>.png for every image; throws IoError naming the file.
void writePlanImages(const PlanResult& result, const std::string& dir, const std::string& prefix, int scale = 2);

/// The floor grid as a greyscale PNG in map_server's convention (floor 254, obstacle 0, unknown 205,
/// row 0 = highest y, one pixel per cell) and its YAML (image, resolution, origin [x, y, 0], ...):
/// the georeferenced map the run report draws the trajectory over.
std::string floorMapPng(const PlanResult& result);
std::string floorMapYaml(const PlanResult& result, const std::string& image);

/// One JSON object: success, message, complete, complete_reason, target {x, y}, score, cost_m,
/// coverage, areas, open_cells, landmarks, path [{x, y, scan}], timings_ms.
std::string planToJson(const PlanResult& result);
/// "x,y,scan" lines (header first) of the path [m].
std::string pathToCsv(const PlanResult& result);

/// Floor states as occupancy values: floor 0, obstacle 100, unknown -1 (row-major, row 0 = lowest y).
std::vector<int8_t> statesToOccupancy(const cv::Mat& states);
/// Accessible 0, floor the robot cannot reach with its body 60, obstacle 100, unknown -1.
std::vector<int8_t> accessibleToOccupancy(const cv::Mat& states, const cv::Mat& accessible);
/// A CV_32F layer scaled to 0..100 by its largest finite value where `valid` (CV_8U) is set,
/// -1 elsewhere.
std::vector<int8_t> scaledToOccupancy(const cv::Mat& values, const cv::Mat& valid);

}  // namespace explorer
}  // namespace scanstop
