file(REMOVE_RECURSE
  "libcalbench_calibration.a"
)
