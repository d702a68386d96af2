#include "devices/usb_transport.hpp"

#include <ftdi.h>
#include <hidapi.h>

#include <chrono>
#include <thread>

#include "devices/spi_bus.hpp"

namespace calbench::devices {
namespace {

class HidapiEndpoint : public HidEndpoint {
 public:
  explicit HidapiEndpoint(hid_device* dev) : dev_(dev) {}
  ~HidapiEndpoint() override { hid_close(dev_); }
  void write(const Bytes& report) override {
    Bytes buf(65, 0);  // report ID 0x00 first, then the 64-byte command
    for (std::size_t i = 0; i < report.size() && i < 64; ++i) buf[i + 1] = report[i];
    if (hid_write(dev_, buf.data(), buf.size()) < 0) throw SpiError("hidapi: write failed: " + err());
  }
  Bytes read(int timeout_ms) override {
    Bytes buf(64, 0);
    const int n = hid_read_timeout(dev_, buf.data(), buf.size(), timeout_ms);
    if (n < 0) throw SpiError("hidapi: read failed: " + err());
    if (n == 0) return {};
    buf.resize(static_cast<std::size_t>(n));
    return buf;
  }

 private:
  std::string err() {
    const wchar_t* w = hid_error(dev_);
    std::string s;
    if (w) for (; *w; ++w) s.push_back(*w < 128 ? static_cast<char>(*w) : '?');
    return s;
  }
  hid_device* dev_;
};

class LibftdiEndpoint : public FtdiEndpoint {
 public:
  explicit LibftdiEndpoint(ftdi_context* ctx) : ctx_(ctx) {}
  ~LibftdiEndpoint() override {
    ftdi_set_bitmode(ctx_, 0, BITMODE_RESET);
    ftdi_usb_close(ctx_);
    ftdi_free(ctx_);
  }
  void write(const Bytes& bytes) override {
    std::size_t off = 0;
    while (off < bytes.size()) {
      const int n = ftdi_write_data(ctx_, bytes.data() + off, static_cast<int>(bytes.size() - off));
      if (n < 0) throw SpiError(std::string("libftdi: write failed: ") + ftdi_get_error_string(ctx_));
      off += static_cast<std::size_t>(n);
    }
  }
  Bytes read(std::size_t n, int timeout_ms) override {
    Bytes out(n);
    std::size_t got = 0;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (got < n) {
      const int r = ftdi_read_data(ctx_, out.data() + got, static_cast<int>(n - got));
      if (r < 0) throw SpiError(std::string("libftdi: read failed: ") + ftdi_get_error_string(ctx_));
      got += static_cast<std::size_t>(r);
      if (got < n) {
        if (std::chrono::steady_clock::now() > deadline) break;
        if (r == 0) std::this_thread::sleep_for(std::chrono::microseconds(50));
      }
    }
    out.resize(got);
    return out;
  }
  void purge() override { ftdi_tcioflush(ctx_); }

 private:
  ftdi_context* ctx_;
};

}  // namespace

std::unique_ptr<HidEndpoint> open_hidapi(std::uint16_t vid, std::uint16_t pid, const std::string& serial) {
  if (hid_init() != 0) throw SpiError("hidapi: hid_init failed");
  std::wstring wserial(serial.begin(), serial.end());
  hid_device* dev = hid_open(vid, pid, serial.empty() ? nullptr : wserial.c_str());
  if (!dev) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "hidapi: no device %04x:%04x%s%s (present? udev rule for /dev/hidraw*?)",
                  vid, pid, serial.empty() ? "" : " serial ", serial.c_str());
    throw SpiError(buf);
  }
  return std::make_unique<HidapiEndpoint>(dev);
}

std::unique_ptr<FtdiEndpoint> open_libftdi(std::uint16_t vid, std::uint16_t pid, const std::string& serial) {
  ftdi_context* ctx = ftdi_new();
  if (!ctx) throw SpiError("libftdi: ftdi_new failed");
  ftdi_set_interface(ctx, INTERFACE_A);
  const int rc = ftdi_usb_open_desc(ctx, vid, pid, nullptr, serial.empty() ? nullptr : serial.c_str());
  if (rc < 0) {
    std::string msg = std::string("libftdi: cannot open FT232H: ") + ftdi_get_error_string(ctx);
    ftdi_free(ctx);
    throw SpiError(msg);
  }
  ftdi_usb_reset(ctx);
  ftdi_set_latency_timer(ctx, 1);
  ftdi_set_bitmode(ctx, 0, BITMODE_RESET);
  ftdi_set_bitmode(ctx, 0, BITMODE_MPSSE);
  ftdi_tcioflush(ctx);
  return std::make_unique<LibftdiEndpoint>(ctx);
}

}  // namespace calbench::devices
