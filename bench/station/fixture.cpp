#include "bench/station/fixture.hpp"

#include <cctype>
#include <cmath>
#include <map>
#include <toml++/toml.h>

#include "bench/io/slot_name.hpp"
#include "bench/io/toml_read.hpp"
#include "bench/io/toml_text.hpp"
#include "calibration/ins/nav_math.hpp"
#include "common/input_error.hpp"
#include "common/units.hpp"
#include "devices/imu_open.hpp"

namespace calbench::station {
namespace {

constexpr int kMaxSlots = 16;

// Slot axes → fixture axes from roll, pitch, yaw in degrees (z-y-x, as a drive's mounting).
Mat3 rpy_rotation(const Vec3& rpy_deg) { return ins::dcm_from_rpy(rpy_deg * units::kDeg); }

// What makes a slot's IMU unusable on its own ("" when none): the same for an emulated and a real run.
std::string slot_imu_problem(const devices::ImuUri& u) {
  if (u.emulated())
    return std::string("'").append(u.text()).append(
        "': a fixture slot is a unit on a bridge (the station emulates its units with --emulated)");
  return devices::cannot_open(u);
}

// Bus arbitration, the same for an emulated and a real run: one bridge per unit (each reads its
// data-ready stream at the full output rate). Units on one bridge's chip selects would share its
// time: not built; refused before anything moves.
void check_one_bridge_per_unit(const Fixture& fx) {
  std::map<std::string, std::string> bridges;
  for (const auto& s : fx.slots)
    if (const auto [it, fresh] = bridges.emplace(s.uri.bridge(), s.name); !fresh)
      throw InputError(fx.file, s.line, "imu",
                       "slots '" + it->second + "' and '" + s.name + "' share the bridge " + s.uri.kind +
                           (s.uri.serial.empty() ? "" : ":" + s.uri.serial) +
                           ": time-slicing one bridge between units is not supported; give each unit its own bridge");
}

}  // namespace

Fixture load_fixture(const std::filesystem::path& file) {
  TomlReader c{file.string()};
  const toml::table root = parse_toml_file(file);
  c.check_keys(root, "", {"fixture", "slot"});
  Fixture fx;
  fx.file = file.string();
  fx.name = file.stem().string();
  if (const toml::node* n = root.get("fixture")) {
    const toml::table* t = n->as_table();
    if (!t) c.fail(n, "fixture", "expected a table [fixture]");
    c.check_keys(*t, "fixture.", {"name", "description"});
    fx.name = c.str(*t, "fixture.", "name", fx.name);
    (void)c.str(*t, "fixture.", "description", std::string());
  }
  const toml::node* sn = root.get("slot");
  const toml::array* slots = sn ? sn->as_array() : nullptr;
  if (!slots || slots->empty()) c.fail(root, "slot", "a fixture needs at least one [[slot]]");
  if (slots->size() > kMaxSlots)
    c.fail(sn, "slot", "at most " + std::to_string(kMaxSlots) + " slots, not " + std::to_string(slots->size()));
  std::map<std::string, std::string> names;         // slot name → key of its first use
  std::map<std::string, std::string> chip_selects;  // bridge + cs → key
  std::map<std::string, std::pair<bool, std::string>> kinds;  // bridge kind → (without serial?, key)
  for (std::size_t i = 0; i < slots->size(); ++i) {
    const std::string pre = "slot[" + std::to_string(i + 1) + "].";
    const toml::table* t = (*slots)[i].as_table();
    if (!t) c.fail(&(*slots)[i], "slot[" + std::to_string(i + 1) + "]", "expected a table");
    c.check_keys(*t, pre, {"name", "imu", "rotation_deg", "offset_mm"});
    FixtureSlot s;
    s.line = static_cast<int>(t->source().begin.line);
    s.name = c.str(*t, pre, "name", std::nullopt);
    if (!valid_slot_name(s.name)) c.fail(t->get("name"), pre + "name", "'" + s.name + "': " + kSlotNameRule);
    if (const auto [it, fresh] = names.emplace(s.name, pre + "name"); !fresh)
      c.fail(t->get("name"), pre + "name", "duplicate slot '" + s.name + "' (also " + it->second + ")");
    s.imu = c.str(*t, pre, "imu", std::nullopt);
    try {
      s.uri = devices::parse_imu_uri(s.imu);
    } catch (const std::invalid_argument& e) {
      c.fail(t->get("imu"), pre + "imu", e.what());
    }
    if (const std::string why = slot_imu_problem(s.uri); !why.empty()) c.fail(t->get("imu"), pre + "imu", why);
    const std::string where = s.uri.bridge() + "#cs" + std::to_string(s.uri.cs);
    if (const auto [it, fresh] = chip_selects.emplace(where, pre + "imu"); !fresh)
      c.fail(t->get("imu"), pre + "imu",
             "'" + s.imu + "': the same bridge and chip select as " + it->second + " (two units on one chip select)");
    // A bridge without serial number is "the only one of its kind attached": then every slot of that kind
    // is on it (on different chip selects); otherwise each names its bridge's serial number.
    if (const auto [it, fresh] = kinds.emplace(s.uri.kind, std::make_pair(s.uri.serial.empty(), pre + "imu"));
        !fresh && it->second.first != s.uri.serial.empty())
      c.fail(t->get("imu"), pre + "imu",
             "'" + s.imu + "': " + it->second.second + " and this slot both use a " + s.uri.kind +
                 ", one without a serial number (the only one attached): name each bridge's serial (KIND:SERIAL)");
    s.rotation_deg = c.vec3(*t, pre, "rotation_deg", Vec3::Zero());
    if (s.rotation_deg.cwiseAbs().maxCoeff() > 360) c.fail(t->get("rotation_deg"), pre + "rotation_deg", "angles within ±360°");
    s.pose.C_f_s = rpy_rotation(s.rotation_deg);
    const Vec3 off_mm = c.vec3(*t, pre, "offset_mm", Vec3::Zero());
    if (off_mm.norm() > 1000) c.fail(t->get("offset_mm"), pre + "offset_mm", "more than 1 m from the centre of rotation");
    s.pose.r_f = off_mm * 1e-3;
    fx.slots.push_back(s);
  }
  check_one_bridge_per_unit(fx);
  return fx;
}

Fixture emulated_fixture(int units) {
  Fixture fx;
  fx.name = "emulated-" + std::to_string(units);
  for (int k = 0; k < units; ++k) {
    FixtureSlot s;
    s.name = std::to_string(k + 1);
    const double a = 2 * M_PI * k / units;
    s.rotation_deg = Vec3(0, 0, 90.0 * (k % 4));
    s.pose.C_f_s = rpy_rotation(s.rotation_deg);
    s.pose.r_f = 0.08 * Vec3(std::cos(a), std::sin(a), 0);
    fx.slots.push_back(s);
  }
  return fx;
}

Fixture single_unit_fixture(const std::string& imu_uri) {
  Fixture fx;
  fx.name = "single";
  FixtureSlot s;
  s.name = "unit";
  s.imu = imu_uri;
  if (!imu_uri.empty()) try {
      s.uri = devices::parse_imu_uri(imu_uri);
    } catch (const std::invalid_argument& e) {
      throw InputError("--imu", 0, "", e.what());
    }
  if (const std::string why = imu_uri.empty() ? "" : slot_imu_problem(s.uri); !why.empty()) throw InputError("--imu", 0, "", why);
  fx.slots.push_back(s);
  return fx;
}

}  // namespace calbench::station
