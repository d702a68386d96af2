
# Consider dependencies only in project.
set(CMAKE_DEPENDS_IN_PROJECT_ONLY OFF)

# The set of languages for which implicit dependencies are needed:
set(CMAKE_DEPENDS_LANGUAGES
  )

# The set of dependency files which are needed:
set(CMAKE_DEPENDS_DEPENDENCY_FILES
  "/work/main/bench/bench_recording.cpp" "CMakeFiles/calbench_bench.dir/bench/bench_recording.cpp.o" "gcc" "CMakeFiles/calbench_bench.dir/bench/bench_recording.cpp.o.d"
  "/work/main/bench/diagnose/diagnose_run.cpp" "CMakeFiles/calbench_bench.dir/bench/diagnose/diagnose_run.cpp.o" "gcc" "CMakeFiles/calbench_bench.dir/bench/diagnose/diagnose_run.cpp.o.d"
  "/work/main/bench/diagnose/effects_json.cpp" "CMakeFiles/calbench_bench.dir/bench/diagnose/effects_json.cpp.o" "gcc" "CMakeFiles/calbench_bench.dir/bench/diagnose/effects_json.cpp.o.d"
  "/work/main/bench/drive/route_toml.cpp" "CMakeFiles/calbench_bench.dir/bench/drive/route_toml.cpp.o" "gcc" "CMakeFiles/calbench_bench.dir/bench/drive/route_toml.cpp.o.d"
  "/work/main/bench/drive/simulate_drive.cpp" "CMakeFiles/calbench_bench.dir/bench/drive/simulate_drive.cpp.o" "gcc" "CMakeFiles/calbench_bench.dir/bench/drive/simulate_drive.cpp.o.d"
  "/work/main/bench/io/coefficients_json.cpp" "CMakeFiles/calbench_bench.dir/bench/io/coefficients_json.cpp.o" "gcc" "CMakeFiles/calbench_bench.dir/bench/io/coefficients_json.cpp.o.d"
  "/work/main/bench/io/csv.cpp" "CMakeFiles/calbench_bench.dir/bench/io/csv.cpp.o" "gcc" "CMakeFiles/calbench_bench.dir/bench/io/csv.cpp.o.d"
  "/work/main/bench/io/json_util.cpp" "CMakeFiles/calbench_bench.dir/bench/io/json_util.cpp.o" "gcc" "CMakeFiles/calbench_bench.dir/bench/io/json_util.cpp.o.d"
  "/work/main/bench/io/plan_toml.cpp" "CMakeFiles/calbench_bench.dir/bench/io/plan_toml.cpp.o" "gcc" "CMakeFiles/calbench_bench.dir/bench/io/plan_toml.cpp.o.d"
  "/work/main/bench/io/recording.cpp" "CMakeFiles/calbench_bench.dir/bench/io/recording.cpp.o" "gcc" "CMakeFiles/calbench_bench.dir/bench/io/recording.cpp.o.d"
  "/work/main/bench/report/db_report.cpp" "CMakeFiles/calbench_bench.dir/bench/report/db_report.cpp.o" "gcc" "CMakeFiles/calbench_bench.dir/bench/report/db_report.cpp.o.d"
  "/work/main/bench/report/gnuplot.cpp" "CMakeFiles/calbench_bench.dir/bench/report/gnuplot.cpp.o" "gcc" "CMakeFiles/calbench_bench.dir/bench/report/gnuplot.cpp.o.d"
  )

# Targets to which this target links.
set(CMAKE_TARGET_LINKED_INFO_FILES
  "/work/main/build/CMakeFiles/calbench_calibration.dir/DependInfo.cmake"
  "/work/main/build/CMakeFiles/calbench_devices.dir/DependInfo.cmake"
  "/work/main/build/CMakeFiles/calbench_db.dir/DependInfo.cmake"
  )

# Fortran module output directory.
set(CMAKE_Fortran_TARGET_MODULE_DIR "")
