file(REMOVE_RECURSE
  "CMakeFiles/calbench.dir/bench/cli/cmd_db.cpp.o"
  "CMakeFiles/calbench.dir/bench/cli/cmd_db.cpp.o.d"
  "CMakeFiles/calbench.dir/bench/cli/cmd_diagnose.cpp.o"
  "CMakeFiles/calbench.dir/bench/cli/cmd_diagnose.cpp.o.d"
  "CMakeFiles/calbench.dir/bench/cli/cmd_emulate.cpp.o"
  "CMakeFiles/calbench.dir/bench/cli/cmd_emulate.cpp.o.d"
  "CMakeFiles/calbench.dir/bench/cli/cmd_fit.cpp.o"
  "CMakeFiles/calbench.dir/bench/cli/cmd_fit.cpp.o.d"
  "CMakeFiles/calbench.dir/bench/cli/cmd_identify.cpp.o"
  "CMakeFiles/calbench.dir/bench/cli/cmd_identify.cpp.o.d"
  "CMakeFiles/calbench.dir/bench/cli/cmd_provision.cpp.o"
  "CMakeFiles/calbench.dir/bench/cli/cmd_provision.cpp.o.d"
  "CMakeFiles/calbench.dir/bench/cli/cmd_report.cpp.o"
  "CMakeFiles/calbench.dir/bench/cli/cmd_report.cpp.o.d"
  "CMakeFiles/calbench.dir/bench/cli/cmd_simulate.cpp.o"
  "CMakeFiles/calbench.dir/bench/cli/cmd_simulate.cpp.o.d"
  "CMakeFiles/calbench.dir/bench/cli/cmd_simulate_drive.cpp.o"
  "CMakeFiles/calbench.dir/bench/cli/cmd_simulate_drive.cpp.o.d"
  "CMakeFiles/calbench.dir/bench/cli/main.cpp.o"
  "CMakeFiles/calbench.dir/bench/cli/main.cpp.o.d"
  "calbench"
  "calbench.pdb"
)

# Per-language clean rules from dependency scanning.
foreach(lang CXX)
  include(CMakeFiles/calbench.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
