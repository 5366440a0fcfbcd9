#include "hw/grbl.h"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <sstream>
#include <thread>

#include "core/error.h"

namespace hovs::hw {
namespace {

constexpr double kDeg = M_PI / 180.0;

speed_t BaudConstant(int baud, const std::string& where) {
  switch (baud) {
    case 9600: return B9600;
    case 19200: return B19200;
    case 38400: return B38400;
    case 57600: return B57600;
    case 115200: return B115200;
    case 230400: return B230400;
    default: throw Error(where, "unsupported baud rate " + std::to_string(baud) + " (9600..230400)");
  }
}

std::string Printable(const std::string& s) {
  std::string out;
  for (unsigned char c : s.substr(0, 80)) out += (c >= 32 && c < 127) ? static_cast<char>(c) : '?';
  return out;
}

}  // namespace

SerialPort::SerialPort(const std::string& path, int baud) : path_(path) {
  const speed_t speed = BaudConstant(baud, path);
  fd_ = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC);
  HOVS_REQUIRE(fd_ >= 0, path, "cannot open the serial port: ", std::strerror(errno));
  termios t{};
  if (tcgetattr(fd_, &t) != 0) {
    ::close(fd_);
    throw Error(path, std::string("not a serial port: ") + std::strerror(errno));
  }
  cfmakeraw(&t);
  cfsetispeed(&t, speed);
  cfsetospeed(&t, speed);
  t.c_cflag |= CLOCAL | CREAD;
  t.c_cc[VMIN] = 0;
  t.c_cc[VTIME] = 0;
  tcsetattr(fd_, TCSANOW, &t);
}

SerialPort::~SerialPort() {
  if (fd_ >= 0) ::close(fd_);
}

void SerialPort::Write(const std::string& bytes) {
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    HOVS_REQUIRE(n > 0, path_, "the port closed while writing (", std::strerror(errno), ")");
    done += static_cast<size_t>(n);
  }
}

std::optional<std::string> SerialPort::ReadLine(double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    const size_t nl = pending_.find('\n');
    if (nl != std::string::npos) {
      std::string line = pending_.substr(0, nl);
      pending_.erase(0, nl + 1);
      while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
      if (line.empty()) continue;  // GRBL's blank lines around its greeting
      return line;
    }
    const double left = std::chrono::duration<double>(end - std::chrono::steady_clock::now()).count();
    if (left <= 0) return std::nullopt;
    pollfd p{fd_, POLLIN, 0};
    const int r = ::poll(&p, 1, static_cast<int>(std::ceil(left * 1000)));
    if (r < 0 && errno == EINTR) continue;
    HOVS_REQUIRE(r >= 0, path_, "cannot read the port: ", std::strerror(errno));
    if (r == 0) return std::nullopt;
    HOVS_REQUIRE(!(p.revents & (POLLHUP | POLLERR)) || (p.revents & POLLIN), path_, "the port closed");
    char buf[256];
    const ssize_t n = ::read(fd_, buf, sizeof buf);
    if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
    HOVS_REQUIRE(n > 0, path_, "the port closed");
    pending_.append(buf, static_cast<size_t>(n));
    HOVS_REQUIRE(pending_.size() < 65536, path_, "a line of more than 64 KiB: not a GRBL controller");
  }
}

GrblOptions GrblOptions::BenchRig() {
  GrblOptions o;
  o.axes = {{rig::AxisId::kX, {'X', false}},    {rig::AxisId::kY, {'Y', false}},
            {rig::AxisId::kRod, {'Z', false}},  {rig::AxisId::kTiltX, {'A', true}},
            {rig::AxisId::kTiltY, {'B', true}}, {rig::AxisId::kTurret, {'C', true}}};
  return o;
}

class GrblMachine::GrblAxis final : public rig::Axis {
 public:
  GrblAxis(GrblMachine* m, rig::AxisId id) : m_(m), id_(id) {}
  rig::AxisId id() const override { return id_; }
  const rig::AxisSpec& spec() const override { return m_->specs_[static_cast<int>(id_)]; }
  void MoveTo(double target) override {
    const rig::AxisSpec& s = spec();
    const std::string where = m_->port_.path() + " (axis " + rig::AxisName(id_) + ")";
    HOVS_REQUIRE(std::isfinite(target) && target >= s.min && target <= s.max, where, "target ",
                 rig::AxisValueText(id_, target), " outside the travel [", rig::AxisValueText(id_, s.min), ", ",
                 rig::AxisValueText(id_, s.max), "]");
    const GrblAxisMap& map = m_->options_.axes.at(id_);
    const double wire = map.rotary ? target / kDeg : target * 1e3;
    char line[96];
    std::snprintf(line, sizeof line, "G90 G0 %c%.4f", map.letter, wire);
    m_->Command(line);
    m_->state_ = "Run";  // until a status says otherwise
    commanded_ = target;
  }
  double Reported() const override { return commanded_ ? *commanded_ : m_->Position(id_); }
  bool Moving() const override { return m_->QueryStatus() != "Idle"; }

 private:
  GrblMachine* m_;
  rig::AxisId id_;
  std::optional<double> commanded_;
};

GrblMachine::GrblMachine(const std::string& port, const std::array<rig::AxisSpec, rig::kAxisCount>& specs,
                         const GrblOptions& options)
    : port_(port, options.baud), options_(options), specs_(specs), start_(std::chrono::steady_clock::now()) {
  HOVS_REQUIRE(options.reply_timeout_s > 0 && options.poll_interval_s > 0, port, "timeouts must be positive");
  for (const auto& [id, map] : options.axes) {
    HOVS_REQUIRE(std::string("XYZABC").find(map.letter) != std::string::npos, port, "axis letter '", map.letter,
                 "' is not one of GRBL's X Y Z A B C");
    axes_[static_cast<int>(id)] = std::make_unique<GrblAxis>(this, id);
  }
  // A soft reset (Ctrl-X) makes the controller greet again, whether it had just started or not.
  port_.Write("\x18");
  for (;;) {
    const auto line = port_.ReadLine(options.reply_timeout_s);
    HOVS_REQUIRE(line.has_value(), port, "no GRBL greeting within ", options.reply_timeout_s,
                 " s after a reset: is a GRBL controller on this port at ", options.baud, " baud?");
    if (line->rfind("Grbl ", 0) == 0) {
      version_ = line->substr(5, line->find(' ', 5) - 5);
      break;
    }
    HOVS_REQUIRE(line->rfind("[MSG:", 0) == 0, port, "unexpected reply '", Printable(*line),
                 "' while waiting for the GRBL greeting");
  }
  Command("G21");
  Command("G90");
  QueryStatus();
}

GrblMachine::~GrblMachine() = default;

rig::Axis& GrblMachine::axis(rig::AxisId id) {
  HOVS_REQUIRE(axes_[static_cast<int>(id)] != nullptr, port_.path(), "axis ", rig::AxisName(id),
               " is not driven by this controller");
  return *axes_[static_cast<int>(id)];
}

double GrblMachine::Now() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void GrblMachine::Command(const std::string& line) {
  port_.Write(line + "\n");
  for (;;) {
    const auto reply = port_.ReadLine(options_.reply_timeout_s);
    HOVS_REQUIRE(reply.has_value(), port_.path(), "no reply within ", options_.reply_timeout_s, " s to '", line, "'");
    if (*reply == "ok") return;
    if (reply->rfind("error:", 0) == 0)
      throw Error(port_.path(), "the controller refused '" + line + "' (" + *reply + ")");
    if (reply->rfind("ALARM:", 0) == 0)
      throw Error(port_.path(), "the controller is in alarm (" + *reply + ") after '" + line + "'; home it");
    if (reply->rfind("[MSG:", 0) == 0 || reply->front() == '<') continue;  // messages and status reports
    throw Error(port_.path(), "unexpected reply '" + Printable(*reply) + "' to '" + line + "'");
  }
}

std::string GrblMachine::QueryStatus() {
  port_.Write("?");
  for (;;) {
    const auto reply = port_.ReadLine(options_.reply_timeout_s);
    HOVS_REQUIRE(reply.has_value(), port_.path(), "no status report within ", options_.reply_timeout_s, " s");
    if (reply->rfind("ALARM:", 0) == 0)
      throw Error(port_.path(), "the controller is in alarm (" + *reply + "); home it");
    if (reply->rfind("[MSG:", 0) == 0 || *reply == "ok") continue;
    HOVS_REQUIRE(reply->size() > 2 && reply->front() == '<' && reply->back() == '>', port_.path(), "unexpected reply '",
                 Printable(*reply), "' to a status query");
    const std::string body = reply->substr(1, reply->size() - 2);
    std::stringstream fields(body);
    std::string field;
    std::getline(fields, state_, '|');
    state_ = state_.substr(0, state_.find(':'));  // "Hold:0" -> "Hold"
    while (std::getline(fields, field, '|')) {
      if (field.rfind("MPos:", 0) != 0) continue;
      std::stringstream values(field.substr(5));
      std::string v;
      const std::string letters = "XYZABC";
      for (size_t i = 0; std::getline(values, v, ',') && i < letters.size(); ++i) {
        char* end = nullptr;
        const double x = std::strtod(v.c_str(), &end);
        HOVS_REQUIRE(end && *end == 0 && std::isfinite(x), port_.path(), "bad position '", Printable(v),
                     "' in the status '", Printable(*reply), "'");
        for (const auto& [id, map] : options_.axes)
          if (map.letter == letters[i]) position_[static_cast<int>(id)] = map.rotary ? x * kDeg : x * 1e-3;
      }
    }
    HOVS_REQUIRE(state_ != "Alarm", port_.path(), "the controller is in alarm; home it");
    return state_;
  }
}

double GrblMachine::Position(rig::AxisId id) const { return position_[static_cast<int>(id)]; }

void GrblMachine::WaitIdle(double timeout_s) {
  const double end = Now() + timeout_s;
  while (QueryStatus() != "Idle") {
    HOVS_REQUIRE(Now() < end, port_.path(), "the axes still move after ", timeout_s, " s (state ", state_, ")");
    std::this_thread::sleep_for(std::chrono::duration<double>(options_.poll_interval_s));
  }
}

}  // namespace hovs::hw
