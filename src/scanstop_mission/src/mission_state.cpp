#include "scanstop_mission/mission_state.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <stdexcept>

#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"

namespace scanstop {
namespace mission {
namespace {

const char* const kStateNames[] = {"IDLE",   "SCANNING", "REGISTERING", "PLANNING", "DRIVING",
                                   "PAUSED", "MESHING",  "DONE",        "ABORTED",  "FAILED"};

YAML::Node poseNode(const Pose2D& p) {
  YAML::Node n(YAML::NodeType::Sequence);
  n.SetStyle(YAML::EmitterStyle::Flow);
  n.push_back(p.x);
  n.push_back(p.y);
  n.push_back(p.yaw);
  return n;
}

Pose2D poseOf(const YAML::Node& n) {
  if (!n.IsSequence() || n.size() != 3) throw std::runtime_error("a pose must be [x, y, yaw]");
  return Pose2D(n[0].as<double>(), n[1].as<double>(), n[2].as<double>());
}

}  // namespace

const char* toString(State s) { return kStateNames[static_cast<int>(s)]; }

State stateFromString(const std::string& s) {
  for (int i = 0; i < 10; ++i)
    if (s == kStateNames[i]) return static_cast<State>(i);
  throw std::invalid_argument("unknown mission state '" + s + "'");
}

void MissionState::save(const std::string& path) const {
  YAML::Node root;
  root["state"] = toString(state);
  root["world"] = world;
  root["collisions"] = collisions;
  root["plans"] = plans;
  root["coverage"] = coverage;
  root["complete"] = complete;
  root["complete_reason"] = complete_reason;
  root["last_error"] = last_error;
  root["elapsed_s"] = elapsed_s;
  root["modelled_time_s"] = modelled_time_s;
  root["modelled_scan_s"] = modelled_scan_s;
  root["modelled_drive_s"] = modelled_drive_s;
  root["modelled_compute_s"] = modelled_compute_s;
  root["last_map_pose"] = poseNode(last_map_pose);
  root["odom_at_last_scan"] = poseNode(odom_at_last_scan);
  root["odom_now"] = poseNode(odom_now);
  YAML::Node path_list(YAML::NodeType::Sequence);
  for (size_t i = 0; i < this->path.size(); ++i) {
    YAML::Node n(YAML::NodeType::Sequence);
    n.SetStyle(YAML::EmitterStyle::Flow);
    n.push_back(this->path[i].x());
    n.push_back(this->path[i].y());
    n.push_back(i < path_scan_at.size() && path_scan_at[i] ? 1 : 0);
    path_list.push_back(n);
  }
  root["path"] = path_list;
  YAML::Node target(YAML::NodeType::Sequence);
  target.SetStyle(YAML::EmitterStyle::Flow);
  target.push_back(path_target.x());
  target.push_back(path_target.y());
  root["path_target"] = target;
  root["path_next"] = path_next;
  root["path_scan_mark"] = path_scan_mark;
  YAML::Node scan_list(YAML::NodeType::Sequence);
  for (const ScanRecord& s : scans) {
    YAML::Node n;
    n["index"] = s.index;
    n["map_pose"] = poseNode(s.map_pose);
    if (s.registered_pose) n["registered_pose"] = poseNode(*s.registered_pose);
    n["odom_pose"] = poseNode(s.odom_pose);
    if (s.true_pose) n["true_pose"] = poseNode(*s.true_pose);
    n["converged"] = s.converged;
    n["rms_m"] = s.rms_m;
    n["valid_points"] = s.valid_points;
    n["scan_time_s"] = s.scan_time_s;
    n["register_wall_s"] = s.register_wall_s;
    n["plan_wall_s"] = s.plan_wall_s;
    n["coverage"] = s.coverage;
    n["mission_time_s"] = s.mission_time_s;
    scan_list.push_back(n);
  }
  root["scans"] = scan_list;
  YAML::Node unreachable_list(YAML::NodeType::Sequence);
  for (const auto& u : unreachable) {
    YAML::Node n(YAML::NodeType::Sequence);
    n.SetStyle(YAML::EmitterStyle::Flow);
    n.push_back(u.x());
    n.push_back(u.y());
    unreachable_list.push_back(n);
  }
  root["unreachable"] = unreachable_list;
  const auto contactList = [](const std::vector<Contact>& list) {
    YAML::Node out(YAML::NodeType::Sequence);
    for (const auto& c : list) {
      YAML::Node n(YAML::NodeType::Sequence);
      n.SetStyle(YAML::EmitterStyle::Flow);
      n.push_back(c.point.x());
      n.push_back(c.point.y());
      n.push_back(c.radius_m);
      out.push_back(n);
    }
    return out;
  };
  root["contacts"] = contactList(contacts);
  root["obstructions"] = contactList(obstructions);
  root["clearance_motions"] = clearance_motions;
  root["clearance_legs"] = clearance_legs;
  root["close_legs"] = close_legs;
  root["min_clearance_m"] = min_clearance_m;
  YAML::Node event_list(YAML::NodeType::Sequence);
  for (const auto& e : events) {
    YAML::Node n;
    n["elapsed_s"] = e.elapsed_s;
    n["what"] = e.what;
    event_list.push_back(n);
  }
  root["events"] = event_list;
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << root;
  writeFileAtomic(path, std::string(out.c_str()) + "\n");
}

MissionState MissionState::load(const std::string& path) {
  const std::string text = readFile(path);
  MissionState m;
  try {
    const YAML::Node root = YAML::Load(text);
    if (!root.IsMap()) throw std::runtime_error("not a mission state (expected a YAML map)");
    m.state = stateFromString(root["state"].as<std::string>());
    m.world = root["world"].as<std::string>("");
    m.collisions = root["collisions"].as<int>(0);
    m.plans = root["plans"].as<int>(0);
    m.coverage = root["coverage"].as<double>(0.0);
    m.complete = root["complete"].as<bool>(false);
    m.complete_reason = root["complete_reason"].as<std::string>("");
    m.last_error = root["last_error"].as<std::string>("");
    m.elapsed_s = root["elapsed_s"].as<double>(0.0);
    m.modelled_time_s = root["modelled_time_s"].as<double>(0.0);
    m.modelled_scan_s = root["modelled_scan_s"].as<double>(0.0);
    m.modelled_drive_s = root["modelled_drive_s"].as<double>(0.0);
    m.modelled_compute_s = root["modelled_compute_s"].as<double>(0.0);
    m.last_map_pose = poseOf(root["last_map_pose"]);
    m.odom_at_last_scan = poseOf(root["odom_at_last_scan"]);
    m.odom_now = poseOf(root["odom_now"]);
    for (const YAML::Node& n : root["scans"]) {
      ScanRecord s;
      s.index = n["index"].as<int>();
      s.map_pose = poseOf(n["map_pose"]);
      if (n["registered_pose"]) s.registered_pose = poseOf(n["registered_pose"]);
      s.odom_pose = poseOf(n["odom_pose"]);
      if (n["true_pose"]) s.true_pose = poseOf(n["true_pose"]);
      s.converged = n["converged"].as<bool>(true);
      s.rms_m = n["rms_m"].as<double>(0.0);
      s.valid_points = n["valid_points"].as<uint32_t>(0);
      s.scan_time_s = n["scan_time_s"].as<double>(0.0);
      s.register_wall_s = n["register_wall_s"].as<double>(0.0);
      s.plan_wall_s = n["plan_wall_s"].as<double>(0.0);
      s.coverage = n["coverage"].as<double>(0.0);
      s.mission_time_s = n["mission_time_s"].as<double>(0.0);
      if (!m.scans.empty() && s.index <= m.scans.back().index)
        throw std::runtime_error("scan indices must increase (" + std::to_string(s.index) + " after " +
                                 std::to_string(m.scans.back().index) + ")");
      m.scans.push_back(s);
    }
    for (const YAML::Node& n : root["path"]) {
      m.path.emplace_back(n[0].as<double>(), n[1].as<double>());
      m.path_scan_at.push_back(n[2].as<int>(0) != 0);
    }
    if (root["path_target"])
      m.path_target = Eigen::Vector2d(root["path_target"][0].as<double>(), root["path_target"][1].as<double>());
    m.path_next = root["path_next"].as<int>(0);
    m.path_scan_mark = root["path_scan_mark"].as<int>(-1);
    if (m.path_next < 0 || m.path_next > static_cast<int>(m.path.size()))
      throw std::runtime_error("path_next " + std::to_string(m.path_next) + " is outside the path of " +
                               std::to_string(m.path.size()) + " waypoints");
    for (const YAML::Node& n : root["unreachable"]) m.unreachable.emplace_back(n[0].as<double>(), n[1].as<double>());
    // [x, y, radius]; contacts of files before the radius: [x, y]; files before obstructions: none
    const auto readContacts = [&root](const char* key, const char* what, std::vector<Contact>& list) {
      for (const YAML::Node& n : root[key]) {
        Contact contact;
        contact.point = Eigen::Vector2d(n[0].as<double>(), n[1].as<double>());
        contact.radius_m = n.size() > 2 ? n[2].as<double>() : 0.0;
        if (!contact.point.allFinite() || !std::isfinite(contact.radius_m) || contact.radius_m < 0.0 ||
            contact.radius_m > 2.0)
          throw std::runtime_error(std::string(what) + " (" + std::to_string(contact.point.x()) + ", " +
                                   std::to_string(contact.point.y()) + ") radius " + std::to_string(contact.radius_m) +
                                   " is not finite or not in [0, 2] m");
        list.push_back(contact);
      }
    };
    readContacts("contacts", "contact", m.contacts);
    readContacts("obstructions", "obstruction", m.obstructions);
    m.clearance_motions = root["clearance_motions"].as<int>(0);
    m.clearance_legs = root["clearance_legs"].as<int>(0);
    m.close_legs = root["close_legs"].as<int>(0);
    m.min_clearance_m = root["min_clearance_m"].as<double>(-1.0);
    for (const YAML::Node& n : root["events"])
      m.events.push_back({n["elapsed_s"].as<double>(), n["what"].as<std::string>()});
  } catch (const std::exception& e) {
    throw IoError(path, std::string("corrupt mission state: ") + e.what());
  }
  return m;
}

}  // namespace mission
}  // namespace scanstop
