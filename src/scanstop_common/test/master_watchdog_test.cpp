#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "scanstop_common/error.h"
#include "scanstop_common/master_watchdog.h"

namespace scanstop {
namespace {

using Event = MasterWatchdog::Event;
using State = MasterWatchdog::State;
const char* const kUri = "http://127.0.0.1:11471";

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// ok -> lost since t -> timeout: the ERROR names the URI and how long the master has been gone, once.
TEST(MasterWatchdog, LostOnceThenTimedOutNamingTheUriAndHowLong) {
  MasterWatchdog w(kUri, 10.0);
  EXPECT_EQ(w.update(100.0, true, 42), Event::None);
  EXPECT_EQ(w.update(100.5, true, 42), Event::None);
  EXPECT_EQ(w.state(), State::Ok);
  EXPECT_EQ(w.update(101.0, false), Event::Lost);
  EXPECT_EQ(w.state(), State::Lost);
  // Gone since the last check that reached it (100.5).
  EXPECT_TRUE(contains(w.message(), "the ROS master at http://127.0.0.1:11471 is unreachable (gone for 0.5 s)"))
      << w.message();
  EXPECT_TRUE(contains(w.message(), "master_timeout_s = 10.0 s")) << w.message();
  for (double t = 101.5; t < 110.5; t += 0.5) EXPECT_EQ(w.update(t, false), Event::None) << t;  // said once
  EXPECT_DOUBLE_EQ(w.lostFor(110.0), 9.5);
  EXPECT_EQ(w.update(110.5, false), Event::TimedOut);
  EXPECT_EQ(w.state(), State::TimedOut);
  EXPECT_TRUE(
      contains(w.message(),
               "the ROS master at http://127.0.0.1:11471 has been unreachable for 10.0 s (master_timeout_s = 10.0 s)"))
      << w.message();
  // Final: nothing more, also when the master comes back.
  EXPECT_EQ(w.update(111.0, false), Event::None);
  EXPECT_EQ(w.update(112.0, true, 42), Event::None);
  EXPECT_EQ(w.state(), State::TimedOut);
}

TEST(MasterWatchdog, TheSameMasterBackInTimeIsBackAndCanBeLostAgain) {
  MasterWatchdog w(kUri, 10.0);
  w.update(0.0, true, 7);
  EXPECT_EQ(w.update(1.0, false), Event::Lost);
  EXPECT_EQ(w.update(5.0, false), Event::None);
  EXPECT_EQ(w.update(6.0, true, 7), Event::Back);
  EXPECT_EQ(w.state(), State::Ok);
  EXPECT_TRUE(contains(w.message(), "http://127.0.0.1:11471 is back after 6.0 s")) << w.message();
  EXPECT_DOUBLE_EQ(w.lostFor(7.0), 0.0);
  // A second outage counts from its own start: no timeout at 10 s after the first.
  EXPECT_EQ(w.update(8.0, false), Event::Lost);
  EXPECT_EQ(w.update(15.0, false), Event::None);
  EXPECT_EQ(w.update(16.5, true, -1), Event::Back);  // pid unknown: not a restart
}

// A restarted roscore on the same URI: the node's topics and services are not registered with it.
TEST(MasterWatchdog, ANewMasterOnTheUriIsARestartNotABack) {
  MasterWatchdog w(kUri, 30.0);
  w.update(0.0, true, 100);
  EXPECT_EQ(w.update(1.0, false), Event::Lost);
  EXPECT_EQ(w.update(3.0, true, 200), Event::Restarted);
  EXPECT_EQ(w.state(), State::Restarted);
  EXPECT_TRUE(contains(w.message(), "answers again after 3.0 s, but it is a new master (pid 200, was 100)"))
      << w.message();
  EXPECT_EQ(w.update(4.0, true, 200), Event::None);
  // Restarted between two checks (never seen unreachable).
  MasterWatchdog quick(kUri, 30.0);
  quick.update(0.0, true, 100);
  EXPECT_EQ(quick.update(0.5, true, 101), Event::Restarted);
}

TEST(MasterWatchdog, NoMasterAtTheFirstCheckIsLostFromThen) {
  MasterWatchdog w(kUri, 2.0);
  EXPECT_EQ(w.update(50.0, false), Event::Lost);
  EXPECT_TRUE(contains(w.message(), "gone for 0.0 s")) << w.message();
  EXPECT_EQ(w.update(51.9, false), Event::None);
  EXPECT_EQ(w.update(52.0, false), Event::TimedOut);
}

TEST(MasterWatchdog, TheTimeoutIsValidatedNamingTheParameter) {
  for (double bad : {0.0, -1.0, std::nan(""), HUGE_VAL, 1e9}) {
    try {
      MasterWatchdog w(kUri, bad);
      ADD_FAILURE() << bad << " accepted";
    } catch (const ConfigError& e) {
      EXPECT_TRUE(contains(e.what(), "parameter 'master_timeout_s'")) << e.what();
      EXPECT_TRUE(contains(e.what(), "(0, 86400] s")) << e.what();
    }
  }
  EXPECT_NO_THROW(MasterWatchdog(kUri, 0.5));
}

}  // namespace
}  // namespace scanstop
