# Empty dependencies file for calbench_bench.
# This may be replaced when dependencies are built.
