// A real motion controller behind rig::Machine: GRBL 1.1's G-code protocol over a serial port (Arduino-class
// controllers and their grblHAL successors drive the turret, rod, lateral and tilt steppers of a bench rig).
//
// Protocol used: the controller greets with "Grbl <version> [...]" on connection; every line sent is answered by
// "ok" or "error:<code>"; an "ALARM:<code>" line reports a fault (a limit switch, lost position); the real-time
// query "?" (no newline) returns "<State|MPos:x,y,z[,a,b,c]|...>". Moves are absolute rapid moves ("G90 G0 X.."),
// in millimetres (G21) for linear axes and degrees for rotary ones; each hovs axis maps to one GRBL axis letter.
// Every failure is a hovs::Error naming the port: an unknown reply, no reply within the timeout, the port closed,
// an error or alarm from the controller (with its code), an axis the controller does not drive.
#pragma once

#include <array>
#include <chrono>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "rig/actuators.h"

namespace hovs::hw {

// A serial line (termios, raw, 8N1). Throws hovs::Error naming the port.
class SerialPort {
 public:
  SerialPort(const std::string& path, int baud);
  ~SerialPort();
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;
  void Write(const std::string& bytes);
  // The next line without its line ending; nullopt after timeout_s. Throws when the port closes.
  std::optional<std::string> ReadLine(double timeout_s);
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int fd_ = -1;
  std::string pending_;
};

struct GrblAxisMap {
  char letter = 'X';    // X Y Z A B C
  bool rotary = false;  // degrees on the wire (the hovs axis is in radians); else millimetres (metres)
};

struct GrblOptions {
  int baud = 115200;
  double reply_timeout_s = 2.0;  // per command
  double poll_interval_s = 0.02;
  std::map<rig::AxisId, GrblAxisMap> axes;  // the hovs axes this controller drives
  // The default map of the bench rig: x X, y Y, rod Z, tilt_x A, tilt_y B, turret C (the focus on the lens' own).
  static GrblOptions BenchRig();
};

class GrblMachine final : public rig::Machine {
 public:
  // Opens the port, waits for the greeting, sets G21 G90. specs: travel and step of every axis (commands outside
  // the travel are refused before they are sent).
  GrblMachine(const std::string& port, const std::array<rig::AxisSpec, rig::kAxisCount>& specs,
              const GrblOptions& options);
  ~GrblMachine() override;
  rig::Axis& axis(rig::AxisId id) override;
  double Now() const override;
  void WaitIdle(double timeout_s) override;
  // Sends one line and waits for "ok" (status reports in between are taken). Throws on error, alarm, timeout.
  void Command(const std::string& line);
  // Queries the status: the state word ("Idle", "Run", "Alarm", ...) and the machine positions in hovs units.
  std::string QueryStatus();
  double Position(rig::AxisId id) const;
  const std::string& version() const { return version_; }

 private:
  class GrblAxis;
  SerialPort port_;
  GrblOptions options_;
  std::array<rig::AxisSpec, rig::kAxisCount> specs_;
  std::array<std::unique_ptr<GrblAxis>, rig::kAxisCount> axes_;
  std::array<double, rig::kAxisCount> position_{};
  std::string state_ = "Unknown", version_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace hovs::hw
