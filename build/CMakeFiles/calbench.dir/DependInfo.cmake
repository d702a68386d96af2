
# Consider dependencies only in project.
set(CMAKE_DEPENDS_IN_PROJECT_ONLY OFF)

# The set of languages for which implicit dependencies are needed:
set(CMAKE_DEPENDS_LANGUAGES
  )

# The set of dependency files which are needed:
set(CMAKE_DEPENDS_DEPENDENCY_FILES
  "/work/main/bench/cli/cmd_db.cpp" "CMakeFiles/calbench.dir/bench/cli/cmd_db.cpp.o" "gcc" "CMakeFiles/calbench.dir/bench/cli/cmd_db.cpp.o.d"
  "/work/main/bench/cli/cmd_diagnose.cpp" "CMakeFiles/calbench.dir/bench/cli/cmd_diagnose.cpp.o" "gcc" "CMakeFiles/calbench.dir/bench/cli/cmd_diagnose.cpp.o.d"
  "/work/main/bench/cli/cmd_emulate.cpp" "CMakeFiles/calbench.dir/bench/cli/cmd_emulate.cpp.o" "gcc" "CMakeFiles/calbench.dir/bench/cli/cmd_emulate.cpp.o.d"
  "/work/main/bench/cli/cmd_fit.cpp" "CMakeFiles/calbench.dir/bench/cli/cmd_fit.cpp.o" "gcc" "CMakeFiles/calbench.dir/bench/cli/cmd_fit.cpp.o.d"
  "/work/main/bench/cli/cmd_identify.cpp" "CMakeFiles/calbench.dir/bench/cli/cmd_identify.cpp.o" "gcc" "CMakeFiles/calbench.dir/bench/cli/cmd_identify.cpp.o.d"
  "/work/main/bench/cli/cmd_provision.cpp" "CMakeFiles/calbench.dir/bench/cli/cmd_provision.cpp.o" "gcc" "CMakeFiles/calbench.dir/bench/cli/cmd_provision.cpp.o.d"
  "/work/main/bench/cli/cmd_report.cpp" "CMakeFiles/calbench.dir/bench/cli/cmd_report.cpp.o" "gcc" "CMakeFiles/calbench.dir/bench/cli/cmd_report.cpp.o.d"
  "/work/main/bench/cli/cmd_simulate.cpp" "CMakeFiles/calbench.dir/bench/cli/cmd_simulate.cpp.o" "gcc" "CMakeFiles/calbench.dir/bench/cli/cmd_simulate.cpp.o.d"
  "/work/main/bench/cli/cmd_simulate_drive.cpp" "CMakeFiles/calbench.dir/bench/cli/cmd_simulate_drive.cpp.o" "gcc" "CMakeFiles/calbench.dir/bench/cli/cmd_simulate_drive.cpp.o.d"
  "/work/main/bench/cli/main.cpp" "CMakeFiles/calbench.dir/bench/cli/main.cpp.o" "gcc" "CMakeFiles/calbench.dir/bench/cli/main.cpp.o.d"
  )

# Targets to which this target links.
set(CMAKE_TARGET_LINKED_INFO_FILES
  "/work/main/build/CMakeFiles/calbench_bench.dir/DependInfo.cmake"
  "/work/main/build/CMakeFiles/calbench_devices.dir/DependInfo.cmake"
  "/work/main/build/CMakeFiles/calbench_db.dir/DependInfo.cmake"
  "/work/main/build/CMakeFiles/calbench_calibration.dir/DependInfo.cmake"
  )

# Fortran module output directory.
set(CMAKE_Fortran_TARGET_MODULE_DIR "")
