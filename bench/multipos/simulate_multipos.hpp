// `calbench simulate multipos`: a multipos recording (meta.json, imu.csv) of a unit turned by hand
// through static poses, with its truth in truth.json beside them (docs/multipos.md "Simulated
// recordings"). The physics is calibration/multipos/multipos_sim.hpp; this reads the options and
// the device class, and writes atomically as the importers do (write_multipos).
#pragma once
#include <cstdint>
#include <optional>
#include <string>

namespace calbench {

struct SimulateMultiposArgs {
  std::string out;
  std::uint64_t seed = 1;
  std::string device_class;  // a class file or the name or alias of a built-in class; empty: ICM-42688-P
  std::string model;                         // meta.json device.model; "" = the class's name
  std::string serial;                        // "" = SIM-<seed>
  int poses = 24;
  std::string still = "1,3";                 // MIN,MAX seconds per pose
  double opening_still_s = 0;
  double noise_factor = 1;
  double rate_hz = 100;
  std::optional<double> site_lat_deg;
  bool force = false;
};

struct SimulateMultiposSummary {
  std::size_t samples = 0;
  int poses = 0;
  double duration_s = 0, rate_hz = 0, gravity_m_s2 = 0;
  std::string device_class, model, out, truth;
};

// Every option is checked before anything is written (InputError naming the option, exit 2).
SimulateMultiposSummary simulate_multipos_recording(const SimulateMultiposArgs& a);

}  // namespace calbench
