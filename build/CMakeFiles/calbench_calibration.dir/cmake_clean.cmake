file(REMOVE_RECURSE
  "CMakeFiles/calbench_calibration.dir/calibration/bench_geometry.cpp.o"
  "CMakeFiles/calbench_calibration.dir/calibration/bench_geometry.cpp.o.d"
  "CMakeFiles/calbench_calibration.dir/calibration/earth.cpp.o"
  "CMakeFiles/calbench_calibration.dir/calibration/earth.cpp.o.d"
  "CMakeFiles/calbench_calibration.dir/calibration/imu_error_sim.cpp.o"
  "CMakeFiles/calbench_calibration.dir/calibration/imu_error_sim.cpp.o.d"
  "CMakeFiles/calbench_calibration.dir/calibration/sensor_model.cpp.o"
  "CMakeFiles/calbench_calibration.dir/calibration/sensor_model.cpp.o.d"
  "CMakeFiles/calbench_calibration.dir/calibration/table_motion.cpp.o"
  "CMakeFiles/calbench_calibration.dir/calibration/table_motion.cpp.o.d"
  "libcalbench_calibration.a"
  "libcalbench_calibration.pdb"
)

# Per-language clean rules from dependency scanning.
foreach(lang CXX)
  include(CMakeFiles/calbench_calibration.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
