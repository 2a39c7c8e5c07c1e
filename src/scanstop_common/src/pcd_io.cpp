// PCD files through PCL; the only translation unit of scanstop_common that includes PCL.
#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <fstream>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"

namespace scanstop {
namespace {

bool hasField(const pcl::PCLPointCloud2& blob, const std::string& name) {
  for (const auto& f : blob.fields)
    if (f.name == name) return true;
  return false;
}

/// Checks the text header before PCL sees the file (PCL's reader crashes on some garbage).
void checkPcdHeader(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  bool fields = false, points = false;
  int lines = 0;
  while (std::getline(in, line) && lines++ < 64) {
    if (line.empty() || line[0] == '#') continue;
    const std::string key = line.substr(0, line.find(' '));
    if (key == "FIELDS" || key == "COLUMNS") fields = true;
    else if (key == "POINTS" || key == "WIDTH") points = true;
    else if (key == "DATA") {
      if (!fields || !points) break;
      return;
    } else if (key != "VERSION" && key != "SIZE" && key != "TYPE" && key != "COUNT" && key != "HEIGHT" &&
               key != "VIEWPOINT") {
      throw IoError(path, "not a valid PCD file: unexpected header line '" + line.substr(0, 40) + "'");
    }
  }
  throw IoError(path, "not a valid PCD file: header lacks FIELDS, WIDTH/POINTS or DATA");
}

}  // namespace

PointCloud readPcd(const std::string& path) {
  {
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw IoError(path, "no such file");
    if (probe.peek() == std::ifstream::traits_type::eof()) throw IoError(path, "empty file");
  }
  checkPcdHeader(path);
  pcl::PCLPointCloud2 blob;
  pcl::PCDReader reader;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int version = 0;
  int status = -1;
  try {
    status = reader.read(path, blob, origin, orientation, version);
  } catch (const std::exception& e) {
    throw IoError(path, std::string("not a valid PCD file: ") + e.what());
  }
  if (status < 0)
    throw IoError(path, "not a valid PCD file (PCL could not parse its header or data)");
  if (!hasField(blob, "x") || !hasField(blob, "y") || !hasField(blob, "z"))
    throw IoError(path, "PCD file lacks x, y or z fields");
  PointCloud cloud;
  const bool normals = hasField(blob, "normal_x") && hasField(blob, "normal_y") && hasField(blob, "normal_z");
  const bool range = hasField(blob, "range");
  if (normals) {
    pcl::PointCloud<pcl::PointNormal> pc;
    pcl::fromPCLPointCloud2(blob, pc);
    cloud.points.reserve(pc.size());
    cloud.normals.reserve(pc.size());
    for (const auto& p : pc.points) {
      cloud.points.emplace_back(p.x, p.y, p.z);
      cloud.normals.emplace_back(p.normal_x, p.normal_y, p.normal_z);
    }
  } else if (range) {
    pcl::PointCloud<pcl::PointWithRange> pc;
    pcl::fromPCLPointCloud2(blob, pc);
    cloud.points.reserve(pc.size());
    cloud.ranges.reserve(pc.size());
    for (const auto& p : pc.points) {
      cloud.points.emplace_back(p.x, p.y, p.z);
      cloud.ranges.push_back(p.range);
    }
  } else {
    pcl::PointCloud<pcl::PointXYZ> pc;
    pcl::fromPCLPointCloud2(blob, pc);
    cloud.points.reserve(pc.size());
    for (const auto& p : pc.points) cloud.points.emplace_back(p.x, p.y, p.z);
  }
  cloud.width = blob.width;
  cloud.height = blob.height;
  if (static_cast<size_t>(cloud.width) * cloud.height != cloud.points.size()) cloud.setUnorganized();
  return cloud;
}

void writePcd(const std::string& path, const PointCloud& cloud) {
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  int result = 0;
  const auto fill = [&cloud](auto& pc) {
    pc.width = cloud.width;
    pc.height = cloud.height;
    pc.is_dense = cloud.countFinite() == cloud.size();
    pc.points.resize(cloud.size());
  };
  if (cloud.hasNormals()) {
    pcl::PointCloud<pcl::PointNormal> pc;
    fill(pc);
    for (size_t i = 0; i < cloud.size(); ++i) {
      auto& q = pc.points[i];
      q.x = cloud.points[i].x(); q.y = cloud.points[i].y(); q.z = cloud.points[i].z();
      q.normal_x = cloud.normals[i].x(); q.normal_y = cloud.normals[i].y(); q.normal_z = cloud.normals[i].z();
      q.curvature = 0.0f;
    }
    result = pcl::io::savePCDFileBinary(tmp, pc);
  } else if (cloud.hasRanges()) {
    pcl::PointCloud<pcl::PointWithRange> pc;
    fill(pc);
    for (size_t i = 0; i < cloud.size(); ++i) {
      auto& q = pc.points[i];
      q.x = cloud.points[i].x(); q.y = cloud.points[i].y(); q.z = cloud.points[i].z();
      q.range = cloud.ranges[i];
    }
    result = pcl::io::savePCDFileBinary(tmp, pc);
  } else {
    pcl::PointCloud<pcl::PointXYZ> pc;
    fill(pc);
    for (size_t i = 0; i < cloud.size(); ++i) {
      auto& q = pc.points[i];
      q.x = cloud.points[i].x(); q.y = cloud.points[i].y(); q.z = cloud.points[i].z();
    }
    result = pcl::io::savePCDFileBinary(tmp, pc);
  }
  if (result < 0) {
    std::remove(tmp.c_str());
    throw IoError(path, "could not write PCD file");
  }
  // PCL's writer does not fsync; flush the data before the rename makes it visible.
  if (FILE* f = std::fopen(tmp.c_str(), "rb+")) {
    ::fsync(fileno(f));
    std::fclose(f);
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw IoError(path, "cannot rename temporary file into place");
  }
}

}  // namespace scanstop
