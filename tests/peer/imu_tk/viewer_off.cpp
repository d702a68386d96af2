// IMU-TK's viewer hooks (declared in its imu_tk/visualization.h) without its Qt4/OpenGL viewer,
// which Debian 12 cannot build: the plots are skipped (they are reached only with verbose output,
// the driver's --verbose; waitForKey returns at once).
#include "imu_tk/visualization.h"

namespace imu_tk {
class Plot::PlotImpl {};
Plot::Plot() {}
template <typename T>
void Plot::plotIntervals(const std::vector<TriadData_<T>>&, const std::vector<DataInterval>&, DataInterval) {}
template void Plot::plotIntervals<double>(const std::vector<TriadData_<double>>&, const std::vector<DataInterval>&, DataInterval);
template void Plot::plotIntervals<float>(const std::vector<TriadData_<float>>&, const std::vector<DataInterval>&, DataInterval);
template <typename T>
void Plot::plotSamples(const std::vector<TriadData_<T>>&, DataInterval) {}
template void Plot::plotSamples<double>(const std::vector<TriadData_<double>>&, DataInterval);
template void Plot::plotSamples<float>(const std::vector<TriadData_<float>>&, DataInterval);
void waitForKey() {}
}  // namespace imu_tk
