// Clocks for the emulators. VirtualClock: emulated time that advances only when someone waits
// (as fast as the CPU allows: tests, benchmarks, the --emulated station). WallClock: real time,
// optionally sped up (the standalone table emulator runs at speed 1).
#pragma once
#include <atomic>
#include <chrono>
#include <thread>

namespace calbench::devices {

class EmuClock {
 public:
  virtual ~EmuClock() = default;
  virtual double now() const = 0;
  // Block (wall clock) or jump (virtual clock) until now() >= t.
  virtual void wait_until(double t) = 0;
  // Time consumed by an operation that takes no real time here (SPI frames on the virtual clock).
  virtual void elapse(double dt) = 0;
};

class VirtualClock : public EmuClock {
 public:
  explicit VirtualClock(double t0 = 0) : t_(t0) {}
  double now() const override { return t_.load(std::memory_order_acquire); }
  void wait_until(double t) override {
    double cur = t_.load();
    while (cur < t && !t_.compare_exchange_weak(cur, t)) {
    }
  }
  void elapse(double dt) override { wait_until(now() + dt); }

 private:
  std::atomic<double> t_;
};

class WallClock : public EmuClock {
 public:
  explicit WallClock(double speed = 1.0) : speed_(speed), t0_(std::chrono::steady_clock::now()) {}
  double now() const override {
    return speed_ * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  }
  void wait_until(double t) override {
    const double d = (t - now()) / speed_;
    if (d > 0) std::this_thread::sleep_for(std::chrono::duration<double>(d));
  }
  void elapse(double) override {}

 private:
  double speed_;
  std::chrono::steady_clock::time_point t0_;
};

}  // namespace calbench::devices
