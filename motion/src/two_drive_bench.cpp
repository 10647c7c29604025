// TwoDriveBench: two single-axis drives as one XY bench (see
// two_drive_bench.hpp), and open_bench (driven_bench.hpp).
#include "motion/two_drive_bench.hpp"

#include <spdlog/spdlog.h>

#include <cmath>
#include <exception>
#include <sstream>
#include <thread>

#include "config/reader.hpp"
#include "motion/errors.hpp"
#include "settle_watch.hpp"

namespace motion {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// The link of one drive: its own URL, or the bench URL with its unit id.
BenchUrl drive_url(const BenchUrl& bench, const AxisDrive& d) {
  if (d.url) return *d.url;
  BenchUrl u = bench;
  u.unit = d.drive.unit_id;  // named in the URL, so that messages tell the drives apart
  return u;
}

const AxisDrives& drives_of(const DriveProfile& p) {
  if (!p.axis_drives) {
    throw ProfileError(p.source +
                       ": a bench of two drives needs [x] and [y] tables; expected a profile of "
                       "two single-axis drives");
  }
  return *p.axis_drives;
}

void refuse_shared_unit(const BenchUrl& url, const DriveProfile& p) {
  const AxisDrives& d = drives_of(p);
  if (url.unit && (!d.x.url || !d.y.url)) {
    throw ProfileError("bench URL " + url.str() + ": ?unit=" + std::to_string(*url.unit) +
                       " names one unit for the two drives of " + p.source +
                       "; expected a URL without ?unit= (each drive's unit is its "
                       "x.link.unit_id / y.link.unit_id)");
  }
}

}  // namespace

TwoDriveBench::TwoDriveBench(const BenchUrl& url, DriveProfile profile)
    : profile_(std::move(profile)) {
  refuse_shared_unit(url, profile_);
  const AxisDrives& d = drives_of(profile_);
  x_ = std::make_unique<ModbusBench>(drive_url(url, d.x), d.x.drive);
  y_ = std::make_unique<ModbusBench>(drive_url(url, d.y), d.y.drive);
}

void TwoDriveBench::stop_quietly(ModbusBench& other, const char* why) {
  try {
    other.stop();
  } catch (const BenchError& e) {
    spdlog::warn("{}: stopping it after {} failed too: {}", other.where(), why, e.what());
  }
}

void TwoDriveBench::home() {
  x_->home();
  try {
    y_->home();
  } catch (const BenchError&) {
    stop_quietly(*x_, "the Y axis drive's home");
    throw;
  }
}

void TwoDriveBench::move_to(double x_mm, double y_mm) {
  const SoftLimits& lim = profile_.soft_limits;
  if (!std::isfinite(x_mm) || !std::isfinite(y_mm) || !lim.contains(x_mm, y_mm)) {
    throw SoftLimitError(lim.refusal(x_mm, y_mm, profile_.source));
  }
  // Both targets are written before either drive starts: a drive that
  // refuses its target leaves both standing.
  x_->write_target(x_mm, 0);
  try {
    y_->write_target(y_mm, 0);
  } catch (const BenchError& e) {
    throw BenchWriteError(std::string(e.what()) +
                          "; neither drive was started: " + holdings(*x_, "its new target") + "; " +
                          holdings(*y_, "what the failed write left"));
  }
  x_->start_move();
  try {
    y_->start_move();
  } catch (const BenchError& e) {
    stop_quietly(*x_, "the Y axis drive's start");
    throw BenchWriteError(std::string(e.what()) + "; the X axis drive had started to " +
                          config::format_number(x_mm) + " mm and was stopped: " +
                          holdings(*x_, "its new target") + "; " + holdings(*y_, "its new target"));
  }
}

std::string TwoDriveBench::holdings(ModbusBench& d, const char* what) {
  std::string s = d.where() + " ";
  try {
    s += "stands at " + config::format_number(d.status().position.x_mm) + " mm";
  } catch (const BenchError&) {
    s += "position unreadable";
  }
  try {
    s += ", its target registers hold " + config::format_number(d.target_registers().x_mm) +
         " mm (" + what + ")";
  } catch (const BenchError&) {
    s += ", its target registers unreadable";
  }
  return s;
}

BenchStatus TwoDriveBench::wait_settled(milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  SettleWatch watch(milliseconds(profile_.timing.settle_time_ms));
  for (;;) {
    BenchStatus sx, sy;
    try {
      sx = x_->checked_status();
    } catch (const BenchFault&) {
      stop_quietly(*y_, "an alarm on the X axis drive");
      throw;
    }
    try {
      sy = y_->checked_status();
    } catch (const BenchFault&) {
      stop_quietly(*x_, "an alarm on the Y axis drive");
      throw;
    }
    const auto now = Clock::now();
    if (watch.settled(x_->on_target(sx) && y_->on_target(sy), now)) return status();
    if (now >= deadline) {
      throw BenchTimeout("bench of two drives (" + profile_.source + "): not settled after " +
                         std::to_string(timeout.count()) + " ms: " + x_->where() + " " +
                         x_->describe_state(sx) + "; " + y_->where() + " " +
                         y_->describe_state(sy));
    }
    std::this_thread::sleep_for(milliseconds(profile_.timing.poll_interval_ms));
  }
}

XY TwoDriveBench::position() {
  return {x_->position().x_mm, y_->position().x_mm};
}

BenchStatus TwoDriveBench::status() {
  const BenchStatus sx = x_->status();
  const BenchStatus sy = y_->status();
  BenchStatus s;
  s.position = {sx.position.x_mm, sy.position.x_mm};
  s.homed = sx.homed && sy.homed;
  s.moving = sx.moving || sy.moving;
  s.in_position = sx.in_position && sy.in_position;
  s.alarm = sx.alarm || sy.alarm;
  s.emergency_stop = sx.emergency_stop || sy.emergency_stop;
  const bool x_first = sx.alarm || (!sy.alarm && sx.alarm_code != 0);
  const BenchStatus& faulty = x_first ? sx : sy;
  s.alarm_code = faulty.alarm_code;
  if (faulty.alarm_code != 0) {
    s.alarm_meaning = std::string(x_first ? "X" : "Y") + " axis: " + faulty.alarm_meaning;
  }
  s.status_word = (sx.status_word & 0xFFFFu) | ((sy.status_word & 0xFFFFu) << 16);
  return s;
}

void TwoDriveBench::stop() {
  std::exception_ptr first;
  for (ModbusBench* d : {x_.get(), y_.get()}) {
    try {
      d->stop();
    } catch (const BenchError&) {
      if (!first) first = std::current_exception();
    }
  }
  if (first) std::rethrow_exception(first);
}

void TwoDriveBench::reset_alarm() {
  std::exception_ptr first;
  for (ModbusBench* d : {x_.get(), y_.get()}) {
    try {
      d->reset_alarm();
    } catch (const BenchError&) {
      if (!first) first = std::current_exception();
    }
  }
  if (first) std::rethrow_exception(first);
}

void TwoDriveBench::set_speed(double speed_mm_s) {
  // Checked on both before either takes it: one speed for both axes, or none.
  x_->check_speed(speed_mm_s);
  y_->check_speed(speed_mm_s);
  x_->set_speed(speed_mm_s);
  y_->set_speed(speed_mm_s);
}

std::unique_ptr<DrivenBench> open_bench(const BenchUrl& url, const DriveProfile& profile) {
  if (profile.axis_drives) return std::make_unique<TwoDriveBench>(url, profile);
  return std::make_unique<ModbusBench>(url, profile);
}

}  // namespace motion
