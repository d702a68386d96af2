# Empty dependencies file for calbench_calibration.
# This may be replaced when dependencies are built.
