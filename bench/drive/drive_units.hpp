// Several MEMS units on one drive (issue 21): a folder with units.json, the drive's reference.csv
// (and gnss.csv) once, and one recording folder per unit (docs/recording-units.md). Each unit folder
// is a whole recording of the interchange format; a multi-unit fit reads the reference once and fits
// every unit against it, side by side.
#pragma once
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/drive/drive_stream.hpp"
#include "bench/drive/fit_drive.hpp"

namespace calbench {

struct DriveUnit {
  std::string slot;
  std::filesystem::path dir;  // the unit's recording folder
};

struct DriveUnits {
  std::filesystem::path dir, reference, gnss;  // gnss: empty when the drive has none
  std::vector<DriveUnit> units;
};

bool is_multi_unit_drive(const std::filesystem::path& dir);  // dir/units.json exists

// Reads and checks units.json: InputError naming the file and key (format, a slot name twice, a unit
// folder that is missing or not a drive recording, a unit whose reference.csv is not the drive's).
DriveUnits load_drive_units(const std::filesystem::path& dir);

struct UnitFit {
  std::string slot;
  std::filesystem::path out;   // its RESULT.json
  DriveResult result;          // RESULT.json (when error is empty)
  std::string error;           // why it failed
  bool bad_input = false;      // the failure was bad input (exit 2)
};

// Fits every unit of the drive with the arguments `a` (a.dir: the drive; a.out: the output folder,
// OUT/SLOT/RESULT.json; a.coeffs: empty, or a folder with SLOT/COEFFS.json or SLOT/RESULT.json per
// unit, as `station run --fixture` and this command write; a.series: a file name, written per unit
// as OUT/SLOT/NAME). The reference is parsed once; the units run on up to `threads` threads (0: one
// per core). Writes OUT/units.json (format calbench-fit-units/1) naming each unit's result. A unit
// that fails does not stop the others; its folder is removed again (if this run made it), and when
// every unit fails neither units.json nor (if this run made it) OUT is left.
std::vector<UnitFit> fit_drive_units(const FitDriveArgs& a, unsigned threads, nlohmann::json* summary = nullptr);

}  // namespace calbench
