
# Consider dependencies only in project.
set(CMAKE_DEPENDS_IN_PROJECT_ONLY OFF)

# The set of languages for which implicit dependencies are needed:
set(CMAKE_DEPENDS_LANGUAGES
  )

# The set of dependency files which are needed:
set(CMAKE_DEPENDS_DEPENDENCY_FILES
  "/work/main/calibration/bench_geometry.cpp" "CMakeFiles/calbench_calibration.dir/calibration/bench_geometry.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/bench_geometry.cpp.o.d"
  "/work/main/calibration/earth.cpp" "CMakeFiles/calbench_calibration.dir/calibration/earth.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/earth.cpp.o.d"
  "/work/main/calibration/imu_error_sim.cpp" "CMakeFiles/calbench_calibration.dir/calibration/imu_error_sim.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/imu_error_sim.cpp.o.d"
  "/work/main/calibration/sensor_model.cpp" "CMakeFiles/calbench_calibration.dir/calibration/sensor_model.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/sensor_model.cpp.o.d"
  "/work/main/calibration/table_motion.cpp" "CMakeFiles/calbench_calibration.dir/calibration/table_motion.cpp.o" "gcc" "CMakeFiles/calbench_calibration.dir/calibration/table_motion.cpp.o.d"
  )

# Targets to which this target links.
set(CMAKE_TARGET_LINKED_INFO_FILES
  )

# Fortran module output directory.
set(CMAKE_Fortran_TARGET_MODULE_DIR "")
