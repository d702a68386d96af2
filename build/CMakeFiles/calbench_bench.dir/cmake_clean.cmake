file(REMOVE_RECURSE
  "CMakeFiles/calbench_bench.dir/bench/bench_recording.cpp.o"
  "CMakeFiles/calbench_bench.dir/bench/bench_recording.cpp.o.d"
  "CMakeFiles/calbench_bench.dir/bench/diagnose/diagnose_run.cpp.o"
  "CMakeFiles/calbench_bench.dir/bench/diagnose/diagnose_run.cpp.o.d"
  "CMakeFiles/calbench_bench.dir/bench/diagnose/effects_json.cpp.o"
  "CMakeFiles/calbench_bench.dir/bench/diagnose/effects_json.cpp.o.d"
  "CMakeFiles/calbench_bench.dir/bench/drive/route_toml.cpp.o"
  "CMakeFiles/calbench_bench.dir/bench/drive/route_toml.cpp.o.d"
  "CMakeFiles/calbench_bench.dir/bench/drive/simulate_drive.cpp.o"
  "CMakeFiles/calbench_bench.dir/bench/drive/simulate_drive.cpp.o.d"
  "CMakeFiles/calbench_bench.dir/bench/io/coefficients_json.cpp.o"
  "CMakeFiles/calbench_bench.dir/bench/io/coefficients_json.cpp.o.d"
  "CMakeFiles/calbench_bench.dir/bench/io/csv.cpp.o"
  "CMakeFiles/calbench_bench.dir/bench/io/csv.cpp.o.d"
  "CMakeFiles/calbench_bench.dir/bench/io/json_util.cpp.o"
  "CMakeFiles/calbench_bench.dir/bench/io/json_util.cpp.o.d"
  "CMakeFiles/calbench_bench.dir/bench/io/plan_toml.cpp.o"
  "CMakeFiles/calbench_bench.dir/bench/io/plan_toml.cpp.o.d"
  "CMakeFiles/calbench_bench.dir/bench/io/recording.cpp.o"
  "CMakeFiles/calbench_bench.dir/bench/io/recording.cpp.o.d"
  "CMakeFiles/calbench_bench.dir/bench/report/db_report.cpp.o"
  "CMakeFiles/calbench_bench.dir/bench/report/db_report.cpp.o.d"
  "CMakeFiles/calbench_bench.dir/bench/report/gnuplot.cpp.o"
  "CMakeFiles/calbench_bench.dir/bench/report/gnuplot.cpp.o.d"
  "libcalbench_bench.a"
  "libcalbench_bench.pdb"
)

# Per-language clean rules from dependency scanning.
foreach(lang CXX)
  include(CMakeFiles/calbench_bench.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
