file(REMOVE_RECURSE
  "CMakeFiles/calbench.dir/bench/cli/main.cpp.o"
  "CMakeFiles/calbench.dir/bench/cli/main.cpp.o.d"
  "calbench"
  "calbench.pdb"
)

# Per-language clean rules from dependency scanning.
foreach(lang CXX)
  include(CMakeFiles/calbench.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
