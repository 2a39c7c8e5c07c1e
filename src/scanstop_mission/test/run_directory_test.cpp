// The run directory knows what it belongs to (issue 22): a finished room_10x8 run reused with
// world:=corridor is refused naming the difference; the same run resumes; a regular file, or a path
// that cannot be created, is refused at once with a named error.
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>

#include <fstream>
#include <string>

#include "scanstop_common/file_util.h"
#include "scanstop_mission/mission_state.h"
#include "scanstop_mission/run_directory.h"

namespace scanstop {
namespace mission {
namespace {

std::string tempDir() {
  char tmpl[] = "/tmp/scanstop_run_dir_test_XXXXXX";
  return ::mkdtemp(tmpl);
}

RunIdentity identityOf(const std::string& world, const std::string& start_pose = "", const std::string& seed = "1") {
  RunIdentity id;
  id.fields = {{"world", world},
               {"world_file_fnv1a64", "0123456789abcdef"},
               {"start_pose", start_pose},
               {"error_profile", "thesis"},
               {"seed", seed},
               {"planes", "400"}};
  return id;
}

/// A saved mission of `world` in `dir` holding `scans` scans.
void saveMission(const std::string& dir, const std::string& world, State state, int scans) {
  MissionState st;
  st.world = world;
  st.state = state;
  st.scans.resize(scans);
  st.save(dir + "/mission_state.yaml");
}

/// A run directory after a run of `id`: the identity and a saved mission with one scan.
std::string finishedRun(const RunIdentity& id) {
  const std::string dir = tempDir() + "/run";
  RunDirectory created(dir, id);
  EXPECT_TRUE(created.created());
  EXPECT_FALSE(created.resumed());
  saveMission(dir, id.fields.at("world"), State::Done, 1);
  return dir;
}

std::string messageOf(const std::string& dir, const RunIdentity& id) {
  try {
    RunDirectory d(dir, id);
  } catch (const RunDirectoryError& e) {
    return e.what();
  }
  return "";
}

TEST(RunDirectory, CreatesTheDirectoryAndRecordsTheIdentity) {
  const std::string dir = tempDir() + "/a/b/run";
  RunDirectory d(dir, identityOf("room_10x8", "1,2,0"));
  EXPECT_TRUE(d.created());
  struct stat st;
  ASSERT_EQ(::stat(dir.c_str(), &st), 0);
  EXPECT_TRUE(S_ISDIR(st.st_mode));
  const RunIdentity saved = RunIdentity::load(d.identityPath());
  EXPECT_EQ(saved.fields.at("world"), "room_10x8");
  EXPECT_EQ(saved.fields.at("start_pose"), "1,2,0");
  EXPECT_EQ(saved.fields.count("created"), 1u);
}

TEST(RunDirectory, ResumesTheSameRun) {
  const std::string dir = finishedRun(identityOf("room_10x8"));
  RunDirectory again(dir, identityOf("room_10x8"));
  EXPECT_TRUE(again.resumed());
  EXPECT_FALSE(again.created());
}

TEST(RunDirectory, RefusesAnotherWorldNamingTheDifferenceAndWhatToDo) {
  const std::string dir = finishedRun(identityOf("room_10x8"));
  RunIdentity corridor = identityOf("corridor");
  corridor.fields["world_file_fnv1a64"] = "fedcba9876543210";
  const std::string msg = messageOf(dir, corridor);
  ASSERT_FALSE(msg.empty()) << "a room_10x8 run directory was accepted for corridor";
  EXPECT_NE(msg.find(dir), std::string::npos) << msg;
  EXPECT_NE(msg.find("world is 'room_10x8' there, 'corridor' now"), std::string::npos) << msg;
  EXPECT_NE(msg.find("world_file_fnv1a64"), std::string::npos) << msg;
  EXPECT_NE(msg.find("use a new run_dir"), std::string::npos) << msg;
  EXPECT_NE(msg.find("delete this one"), std::string::npos) << msg;
  // Nothing of the room's run was touched.
  EXPECT_EQ(RunIdentity::load(dir + "/run_identity.yaml").fields.at("world"), "room_10x8");
  EXPECT_EQ(MissionState::load(dir + "/mission_state.yaml").world, "room_10x8");
}

TEST(RunDirectory, RefusesAnotherStartPoseOrSeed) {
  const std::string dir = finishedRun(identityOf("room_10x8", "1,1,0", "1"));
  EXPECT_NE(messageOf(dir, identityOf("room_10x8", "2,1,0", "1")).find("start_pose is '1,1,0' there, '2,1,0' now"),
            std::string::npos);
  EXPECT_NE(messageOf(dir, identityOf("room_10x8", "1,1,0", "7")).find("seed is '1' there, '7' now"),
            std::string::npos);
}

TEST(RunDirectory, ADirectoryWithoutAMissionTakesTheNewIdentity) {
  // A launch that failed before its first scan (say a typo in start_pose) leaves only the identity:
  // nothing to mix, so the corrected launch may use the directory.
  const std::string dir = tempDir() + "/run";
  { RunDirectory first(dir, identityOf("room_10x8", "garbage")); }
  RunDirectory second(dir, identityOf("room_10x8", "1,1,0"));
  EXPECT_FALSE(second.resumed());
  EXPECT_EQ(RunIdentity::load(second.identityPath()).fields.at("start_pose"), "1,1,0");
}

TEST(RunDirectory, AMissionThatEndedBeforeItsFirstScanIsSetAsideNotDefended) {
  // A launch that ended at start-up (a start pose in a wall) leaves a mission state with no scan; the
  // corrected launch (another start pose) starts afresh there instead of being refused as another run.
  const std::string dir = tempDir() + "/run";
  { RunDirectory first(dir, identityOf("room_10x8", "0,4,0")); }
  saveMission(dir, "room_10x8", State::Aborted, 0);
  RunDirectory second(dir, identityOf("room_10x8", "2,5,0"));
  EXPECT_FALSE(second.resumed());
  EXPECT_EQ(second.setAside(), dir + "/mission_state.yaml.unstarted");
  EXPECT_EQ(MissionState::load(second.setAside()).state, State::Aborted);  // kept, not deleted
  EXPECT_EQ(RunIdentity::load(second.identityPath()).fields.at("start_pose"), "2,5,0");
  // A run that ended at start-up in 0,4,0, with a map/poses.csv of the given text.
  const auto endedWithPoses = [](const std::string& poses) {
    const std::string run = tempDir() + "/run";
    { RunDirectory first(run, identityOf("room_10x8", "0,4,0")); }
    saveMission(run, "room_10x8", State::Aborted, 0);
    EXPECT_EQ(::mkdir((run + "/map").c_str(), 0755), 0);
    writeFileAtomic(run + "/map/poses.csv", poses);
    return run;
  };
  // SLAM had written a poses.csv without a scan line: still nothing to protect.
  const std::string header_only = endedWithPoses("index,file\n");
  RunDirectory corrected(header_only, identityOf("room_10x8", "2,5,0"));
  EXPECT_FALSE(corrected.resumed());
  EXPECT_EQ(RunIdentity::load(corrected.identityPath()).fields.at("start_pose"), "2,5,0");
  // One scan in the map (even when the state lists none) is a mission: another start pose is refused.
  const std::string scanned = endedWithPoses("index,file\n0,scans/scan_0000.pcd\n");
  EXPECT_NE(messageOf(scanned, identityOf("room_10x8", "2,5,0")).find("start_pose is '0,4,0' there"),
            std::string::npos);
  // A state that lists a scan is a mission too.
  const std::string listed = finishedRun(identityOf("room_10x8", "0,4,0"));
  EXPECT_NE(messageOf(listed, identityOf("room_10x8", "2,5,0")).find("start_pose is '0,4,0' there"), std::string::npos);
}

TEST(RunDirectory, AnEarlierVersionsDirectoryIsCheckedByItsMissionsWorld) {
  // No run_identity.yaml: mission_state.yaml's world decides.
  const std::string dir = tempDir();
  saveMission(dir, "room_10x8", State::Done, 2);
  EXPECT_NE(messageOf(dir, identityOf("corridor")).find("world is 'room_10x8' there, 'corridor' now"),
            std::string::npos);
  RunDirectory same(dir, identityOf("room_10x8"));
  EXPECT_TRUE(same.resumed());
  EXPECT_EQ(RunIdentity::load(same.identityPath()).fields.at("world"), "room_10x8");
}

TEST(RunDirectory, RefusesARegularFile) {
  const std::string file = tempDir() + "/not_a_dir";
  std::ofstream(file) << "x";
  const std::string msg = messageOf(file, identityOf("room_10x8"));
  EXPECT_NE(msg.find(file), std::string::npos) << msg;
  EXPECT_NE(msg.find("exists but is a regular file, not a directory"), std::string::npos) << msg;
  // A path below a regular file cannot be created.
  const std::string below = messageOf(file + "/run", identityOf("room_10x8"));
  EXPECT_NE(below.find("cannot create the run directory (Not a directory)"), std::string::npos) << below;
}

TEST(RunDirectory, RefusesAPathThatCannotBeCreated) {
  const std::string msg = messageOf("/proc/scanstop_no_such_dir/run", identityOf("room_10x8"));
  EXPECT_NE(msg.find("cannot create the run directory"), std::string::npos) << msg;
}

TEST(RunDirectory, IdentityDifferencesIgnoreFieldsTheRecordingLacks) {
  RunIdentity recorded, now;
  recorded.fields = {{"world", "room_10x8"}, {"created", "2026-01-01T00:00:00Z"}};
  now.fields = {{"world", "room_10x8"}, {"seed", "3"}};
  EXPECT_EQ(identityDifferences(recorded, now), "");
  now.fields.erase("world");
  EXPECT_EQ(identityDifferences(recorded, now), "world is 'room_10x8' there, '' now");
}

TEST(RunDirectory, FileFingerprintTellsFilesApartAndNamesAMissingOne) {
  const std::string dir = tempDir();
  writeFileAtomic(dir + "/a.stl", "solid a");
  writeFileAtomic(dir + "/b.stl", "solid b");
  writeFileAtomic(dir + "/a_copy.stl", "solid a");
  EXPECT_EQ(fileFingerprint(dir + "/a.stl"), fileFingerprint(dir + "/a_copy.stl"));
  EXPECT_NE(fileFingerprint(dir + "/a.stl"), fileFingerprint(dir + "/b.stl"));
  EXPECT_EQ(fileFingerprint(dir + "/a.stl").size(), 16u);
  EXPECT_THROW(fileFingerprint(dir + "/missing.stl"), IoError);
}

}  // namespace
}  // namespace mission
}  // namespace scanstop
