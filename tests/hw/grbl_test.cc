// The GRBL controller behind rig::Machine, against an emulator on a pseudo-terminal: moves in millimetres and
// degrees, status polling until idle, and every failure ending in one error naming the port: an unknown reply, no
// reply, a closed port, a refusal, an alarm, no greeting, a path that is not a serial port.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <stdlib.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/error.h"
#include "hw/grbl.h"

namespace hovs::hw {
namespace {

// A GRBL 1.1 controller on the master side of a pseudo-terminal: greets after Ctrl-X, answers "ok" to G21 / G90 and
// to absolute moves (which take `move_ms` to finish: "Run" until then), "<State|MPos:...>" to '?'.
class GrblEmulator {
 public:
  enum class Mode { kNormal, kGarbage, kSilent, kClose, kRefuse, kAlarm, kMute };
  explicit GrblEmulator(Mode mode = Mode::kNormal, int move_ms = 60) : mode_(mode), move_ms_(move_ms) {
    master_ = posix_openpt(O_RDWR | O_NOCTTY);
    EXPECT_GE(master_, 0);
    grantpt(master_);
    unlockpt(master_);
    slave_ = ptsname(master_);
    thread_ = std::thread([this] { Loop(); });
  }
  ~GrblEmulator() {
    stop_ = true;
    thread_.join();
    if (master_ >= 0) close(master_);
  }
  const std::string& port() const { return slave_; }
  std::vector<std::string> lines() {
    std::lock_guard<std::mutex> lock(mutex_);
    return lines_;
  }
  double pos[6] = {0, 0, 0, 0, 0, 0};

 private:
  void Send(const std::string& s) {
    if (master_ >= 0) (void)!write(master_, s.data(), s.size());
  }
  bool Moving() const { return std::chrono::steady_clock::now() < busy_until_; }
  void Line(const std::string& line) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      lines_.push_back(line);
    }
    if (line.find("G0") == std::string::npos) return Send("ok\r\n");
    switch (mode_) {
      case Mode::kGarbage: return Send("huh?\r\n");
      case Mode::kSilent: return;
      case Mode::kClose: close(master_), master_ = -1; return;
      case Mode::kRefuse: return Send("error:22\r\n");
      case Mode::kAlarm: return Send("ALARM:1\r\n");
      default: break;
    }
    const std::string letters = "XYZABC";
    for (size_t i = 0; i + 1 < line.size(); ++i) {
      const size_t k = letters.find(line[i]);
      if (k != std::string::npos && line[i - 1] == ' ') pos[k] = std::strtod(line.c_str() + i + 1, nullptr);
    }
    busy_until_ = std::chrono::steady_clock::now() + std::chrono::milliseconds(move_ms_);
    Send("ok\r\n");
  }
  void Loop() {
    std::string buf;
    while (!stop_ && master_ >= 0) {
      pollfd p{master_, POLLIN, 0};
      if (poll(&p, 1, 20) <= 0) continue;
      char c[256];
      const ssize_t n = read(master_, c, sizeof c);
      if (n <= 0) continue;
      for (ssize_t i = 0; i < n; ++i) {
        if (c[i] == '\x18') {
          if (mode_ != Mode::kMute) Send("\r\nGrbl 1.1h ['$' for help]\r\n");
        } else if (c[i] == '?') {
          char s[200];
          std::snprintf(s, sizeof s, "<%s|MPos:%.3f,%.3f,%.3f,%.3f,%.3f,%.3f|FS:0,0>\r\n", Moving() ? "Run" : "Idle",
                        pos[0], pos[1], pos[2], pos[3], pos[4], pos[5]);
          Send(s);
        } else if (c[i] == '\n') {
          Line(buf);
          buf.clear();
        } else if (c[i] != '\r') {
          buf += c[i];
        }
      }
    }
  }
  Mode mode_;
  int move_ms_;
  int master_ = -1;
  std::string slave_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::vector<std::string> lines_;
  std::chrono::steady_clock::time_point busy_until_{};
};

std::array<rig::AxisSpec, rig::kAxisCount> Specs() {
  std::array<rig::AxisSpec, rig::kAxisCount> s;
  for (auto& a : s) a.min = -0.01, a.max = 0.01, a.step = 1e-6;
  s[static_cast<int>(rig::AxisId::kTurret)] = {-0.2, 6.5, 1e-4};
  s[static_cast<int>(rig::AxisId::kRod)] = {0.1, 0.2, 1e-6};
  s[static_cast<int>(rig::AxisId::kTiltX)] = s[static_cast<int>(rig::AxisId::kTiltY)] = {-0.05, 0.05, 1e-5};
  return s;
}

GrblOptions Quick() {
  GrblOptions o = GrblOptions::BenchRig();
  o.reply_timeout_s = 0.5;
  return o;
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) { return e.what(); }
  return "no error";
}

TEST(Grbl, MovesInMillimetresAndDegreesAndWaitsUntilIdle) {
  GrblEmulator emu;
  GrblMachine m(emu.port(), Specs(), Quick());
  EXPECT_EQ(m.version(), "1.1h");
  m.axis(rig::AxisId::kX).MoveTo(0.00125);
  m.axis(rig::AxisId::kRod).MoveTo(0.13023);
  m.axis(rig::AxisId::kTiltX).MoveTo(0.5 * M_PI / 180);
  m.axis(rig::AxisId::kTurret).MoveTo(M_PI / 2);
  EXPECT_TRUE(m.axis(rig::AxisId::kX).Moving());
  const double t0 = m.Now();
  m.WaitIdle(2.0);
  EXPECT_GE(m.Now() - t0, 0.03);  // the emulator's move takes 60 ms
  EXPECT_NEAR(m.Position(rig::AxisId::kX), 0.00125, 1e-9);
  EXPECT_NEAR(m.Position(rig::AxisId::kRod), 0.13023, 1e-9);
  EXPECT_NEAR(m.Position(rig::AxisId::kTiltX), 0.5 * M_PI / 180, 1e-6);
  EXPECT_NEAR(m.Position(rig::AxisId::kTurret), M_PI / 2, 1e-6);
  const auto lines = emu.lines();
  EXPECT_EQ(lines[0], "G21");
  EXPECT_EQ(lines[1], "G90");
  EXPECT_EQ(lines[2], "G90 G0 X1.2500");
  EXPECT_EQ(lines[3], "G90 G0 Z130.2300");
  EXPECT_EQ(lines[4], "G90 G0 A0.5000");
  EXPECT_EQ(lines[5], "G90 G0 C90.0000");
  // An axis this controller does not drive, a target outside the travel: refused before anything is sent.
  EXPECT_NE(ErrorOf([&] { m.axis(rig::AxisId::kFocus); }).find("axis focus is not driven"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { m.axis(rig::AxisId::kY).MoveTo(0.02); }).find("(axis y): target 0.02 m outside the travel"),
            std::string::npos);
  EXPECT_EQ(emu.lines().size(), 6u);
}

TEST(Grbl, EveryFailureIsOneErrorNamingThePort) {
  const auto move_error = [](GrblEmulator::Mode mode) {
    GrblEmulator emu(mode);
    std::string e;
    {
      GrblMachine m(emu.port(), Specs(), Quick());
      e = ErrorOf([&] { m.axis(rig::AxisId::kX).MoveTo(0.001); });
    }
    EXPECT_EQ(e.rfind(emu.port(), 0), 0u) << e;
    return e;
  };
  EXPECT_NE(move_error(GrblEmulator::Mode::kGarbage).find("unexpected reply 'huh?' to 'G90 G0 X1.0000'"),
            std::string::npos);
  EXPECT_NE(move_error(GrblEmulator::Mode::kSilent).find("no reply within 0.5 s to 'G90 G0 X1.0000'"),
            std::string::npos);
  EXPECT_NE(move_error(GrblEmulator::Mode::kClose).find("the port closed"), std::string::npos);
  EXPECT_NE(move_error(GrblEmulator::Mode::kRefuse).find("refused 'G90 G0 X1.0000' (error:22)"), std::string::npos);
  EXPECT_NE(move_error(GrblEmulator::Mode::kAlarm).find("in alarm (ALARM:1)"), std::string::npos);
  {
    GrblEmulator mute(GrblEmulator::Mode::kMute);
    const std::string e = ErrorOf([&] { GrblMachine m(mute.port(), Specs(), Quick()); });
    EXPECT_NE(e.find("no GRBL greeting within 0.5 s"), std::string::npos) << e;
  }
  const std::string file = ::testing::TempDir() + "/not-a-port";
  std::ofstream(file) << "x";
  EXPECT_NE(ErrorOf([&] { GrblMachine m(file, Specs(), Quick()); }).find("not a serial port"), std::string::npos);
  EXPECT_NE(
      ErrorOf([&] { GrblMachine m("/nonexistent/ttyUSB9", Specs(), Quick()); }).find("cannot open the serial port"),
      std::string::npos);
}

}  // namespace
}  // namespace hovs::hw
