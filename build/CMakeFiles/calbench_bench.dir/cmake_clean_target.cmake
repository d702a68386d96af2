file(REMOVE_RECURSE
  "libcalbench_bench.a"
)
