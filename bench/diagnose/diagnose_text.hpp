// Parts of the `calbench diagnose` output shared by the bench (diagnose_run.hpp) and the drive
// (drive_run.hpp): names, display units, the JSON of a finding's value and evidence, the per-axis
// table of the text, the residual plot of the HTML report. The CLI side is split by what it makes:
// diagnose_load.cpp (recordings in), diagnose_json.cpp, diagnose_text.cpp, diagnose_html.cpp;
// diagnose_run.cpp and drive_run.cpp only run the diagnosis and build IMPROVED.json.
#pragma once
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "calibration/diagnosis/diagnose.hpp"

namespace calbench::diagnose_out {

extern const char* const kSensor[3];    // gyro, accel, reference
extern const char* const kAxis[3];      // x, y, z
extern const char* const kAxisName[6];  // gyro_x … accel_z

// Display units of a residual: gyro °/h, accel mg.
double disp(double v, int sensor);
const char* disp_unit(int sensor);

// Bench: a value in the units people use, an RMS in °/h or mg; the axis (0..5) a finding's
// figures are for.
std::string human_value(const DiagFinding& f, double v);
std::string human_rms(int sensor, double v);
int finding_axis_index(const DiagFinding& f, const DiagnoseResult& r);

// A finding's value and σ for the JSON: a number (σ null when not finite) or arrays.
void finding_value_json(const DiagFinding& f, nlohmann::json& value, nlohmann::json& sigma);
// A drive finding's effect, sensor, axis ("all" for none), value, σ and unit.
nlohmann::json finding_head_json(const DiagFinding& f);
// Issue 36's status of a finding into its JSON: established, status ("not told apart" when it is
// not told apart from an alternative), explained_fraction, remainder_is_noise; σ null unless told apart.
void not_established(const DiagFinding& f, nlohmann::json& j);
// evidence: Δχ², ΔBIC, held-out Δχ², revealing condition and its correlation, the drift's τ
// (correlated_drift) and the candidates not told apart.
nlohmann::json finding_evidence_json(const DiagFinding& f);
// [{condition, r}] of the first `most` correlations.
nlohmann::json correlations_json(const std::vector<ConditionCorrelation>& c, std::size_t most);
// " w_z (r 0.52) f_x (r -0.31)" for the text.
std::string correlations_text(const std::vector<ConditionCorrelation>& c);
// "per axis (systematic RMS, χ²/dof, Ljung–Box p) before → after:" and one line per axis, the RMS
// as rms(sensor, value) writes it.
std::string axis_table_text(const DiagnoseResult& r, const std::function<std::string(int, double)>& rms);
// Drives with --coeffs: the bias re-estimated against the given coefficients (the null alternative
// "a turn-on bias shift", in every drive model, so a term whose regressor is nearly constant on the
// drive — g-sensitivity to f_z ≈ −g on a level road — is credited only with what its variation
// explains). change = improved − given, per axis gyro x … accel z (SI); σ of the drive's estimate and
// of the given bias (their bench fit's σ) together; the axes beyond 3σ.
struct BiasChange {
  double change[6] = {}, sigma[6] = {};
  std::vector<int> beyond_3sigma;
};
BiasChange bias_change(const DiagnoseResult& r);
// "bias since the given coefficients (…): gyro +30.1 ± 0.9, … °/h; accel … mg; beyond 3σ: gyro x\n"
std::string bias_change_text(const DiagnoseResult& r);
// IMPROVED.json's extra: the catalogue keys replaced by the improved terms, and "diagnosis".
void improved_extra(nlohmann::json& extra, const DiagnoseResult& r, const nlohmann::json& diagnosis);

}  // namespace calbench::diagnose_out

namespace calbench {
struct DriveInnovations;
struct InnovationStats;
}

namespace calbench::diagnose_out {

// Drive: the observation types of the innovations and one sentence per type.
std::string innovation_sentence(int type, const DriveInnovations& v);
// The JSON of one observation type's innovation statistics (drive_innovations.hpp).
nlohmann::json innovation_stats_json(const InnovationStats& s);

// A before/after residual plot (columns x, before, after in `data`) through the report's gnuplot
// runner: inline SVG (svg) or a PNG <img>; on failure a note saying why.
std::string residual_plot_html(const std::string& data, const std::string& xlabel, const std::string& ylabel,
                               bool svg);

}  // namespace calbench::diagnose_out
