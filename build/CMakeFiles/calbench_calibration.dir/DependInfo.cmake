
# Consider dependencies only in project.
set(CMAKE_DEPENDS_IN_PROJECT_ONLY OFF)

# The set of languages for which implicit dependencies are needed:
set(CMAKE_DEPENDS_LANGUAGES
  )

# The set of dependency files which are needed:
set(CMAKE_DEPENDS_DEPENDENCY_FILES
  "/work/main/calibration/bench_blocks.cpp" "CMakeFiles/calbench_calibration.dir/calibration/bench_blocks.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/bench_blocks.cpp.o.d"
  "/work/main/calibration/bench_fit_common.cpp" "CMakeFiles/calbench_calibration.dir/calibration/bench_fit_common.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/bench_fit_common.cpp.o.d"
  "/work/main/calibration/bench_fit_ekf.cpp" "CMakeFiles/calbench_calibration.dir/calibration/bench_fit_ekf.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/bench_fit_ekf.cpp.o.d"
  "/work/main/calibration/bench_fit_lsq.cpp" "CMakeFiles/calbench_calibration.dir/calibration/bench_fit_lsq.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/bench_fit_lsq.cpp.o.d"
  "/work/main/calibration/bench_geometry.cpp" "CMakeFiles/calbench_calibration.dir/calibration/bench_geometry.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/bench_geometry.cpp.o.d"
  "/work/main/calibration/bench_sim.cpp" "CMakeFiles/calbench_calibration.dir/calibration/bench_sim.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/bench_sim.cpp.o.d"
  "/work/main/calibration/diagnosis/catalogue.cpp" "CMakeFiles/calbench_calibration.dir/calibration/diagnosis/catalogue.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/diagnosis/catalogue.cpp.o.d"
  "/work/main/calibration/diagnosis/diag_data.cpp" "CMakeFiles/calbench_calibration.dir/calibration/diagnosis/diag_data.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/diagnosis/diag_data.cpp.o.d"
  "/work/main/calibration/diagnosis/diagnose.cpp" "CMakeFiles/calbench_calibration.dir/calibration/diagnosis/diagnose.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/diagnosis/diagnose.cpp.o.d"
  "/work/main/calibration/drive_sim/drive_simulator.cpp" "CMakeFiles/calbench_calibration.dir/calibration/drive_sim/drive_simulator.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/drive_sim/drive_simulator.cpp.o.d"
  "/work/main/calibration/drive_sim/route.cpp" "CMakeFiles/calbench_calibration.dir/calibration/drive_sim/route.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/drive_sim/route.cpp.o.d"
  "/work/main/calibration/earth.cpp" "CMakeFiles/calbench_calibration.dir/calibration/earth.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/earth.cpp.o.d"
  "/work/main/calibration/effects/effect_terms.cpp" "CMakeFiles/calbench_calibration.dir/calibration/effects/effect_terms.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/effects/effect_terms.cpp.o.d"
  "/work/main/calibration/identification/allan.cpp" "CMakeFiles/calbench_calibration.dir/calibration/identification/allan.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/identification/allan.cpp.o.d"
  "/work/main/calibration/identification/correlation.cpp" "CMakeFiles/calbench_calibration.dir/calibration/identification/correlation.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/identification/correlation.cpp.o.d"
  "/work/main/calibration/identification/correlation_fit.cpp" "CMakeFiles/calbench_calibration.dir/calibration/identification/correlation_fit.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/identification/correlation_fit.cpp.o.d"
  "/work/main/calibration/identification/noise_processes.cpp" "CMakeFiles/calbench_calibration.dir/calibration/identification/noise_processes.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/identification/noise_processes.cpp.o.d"
  "/work/main/calibration/identification/shaping_filter.cpp" "CMakeFiles/calbench_calibration.dir/calibration/identification/shaping_filter.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/identification/shaping_filter.cpp.o.d"
  "/work/main/calibration/imu_error_sim.cpp" "CMakeFiles/calbench_calibration.dir/calibration/imu_error_sim.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/imu_error_sim.cpp.o.d"
  "/work/main/calibration/inmotion/error_model.cpp" "CMakeFiles/calbench_calibration.dir/calibration/inmotion/error_model.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/inmotion/error_model.cpp.o.d"
  "/work/main/calibration/inmotion/inmotion_filter.cpp" "CMakeFiles/calbench_calibration.dir/calibration/inmotion/inmotion_filter.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/inmotion/inmotion_filter.cpp.o.d"
  "/work/main/calibration/inmotion/obs_attitude.cpp" "CMakeFiles/calbench_calibration.dir/calibration/inmotion/obs_attitude.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/inmotion/obs_attitude.cpp.o.d"
  "/work/main/calibration/inmotion/obs_position.cpp" "CMakeFiles/calbench_calibration.dir/calibration/inmotion/obs_position.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/inmotion/obs_position.cpp.o.d"
  "/work/main/calibration/inmotion/obs_velocity.cpp" "CMakeFiles/calbench_calibration.dir/calibration/inmotion/obs_velocity.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/inmotion/obs_velocity.cpp.o.d"
  "/work/main/calibration/inmotion/state_layout.cpp" "CMakeFiles/calbench_calibration.dir/calibration/inmotion/state_layout.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/inmotion/state_layout.cpp.o.d"
  "/work/main/calibration/ins/nav_math.cpp" "CMakeFiles/calbench_calibration.dir/calibration/ins/nav_math.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/ins/nav_math.cpp.o.d"
  "/work/main/calibration/ins/strapdown.cpp" "CMakeFiles/calbench_calibration.dir/calibration/ins/strapdown.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/ins/strapdown.cpp.o.d"
  "/work/main/calibration/sensor_model.cpp" "CMakeFiles/calbench_calibration.dir/calibration/sensor_model.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/sensor_model.cpp.o.d"
  "/work/main/calibration/table_motion.cpp" "CMakeFiles/calbench_calibration.dir/calibration/table_motion.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/table_motion.cpp.o.d"
  )

# Targets to which this target links.
set(CMAKE_TARGET_LINKED_INFO_FILES
  )

# Fortran module output directory.
set(CMAKE_Fortran_TARGET_MODULE_DIR "")
