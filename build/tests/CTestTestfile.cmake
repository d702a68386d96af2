# CMake generated Testfile for 
# Source directory: /work/main/tests
# Build directory: /work/main/build/tests
# 
# This file includes the relevant testing commands required for 
# testing this directory and lists subdirectories to be tested as well.
include("/work/main/build/tests/test_bench[1]_include.cmake")
include("/work/main/build/tests/test_calibration[1]_include.cmake")
include("/work/main/build/tests/test_db[1]_include.cmake")
include("/work/main/build/tests/test_devices[1]_include.cmake")
add_test([=[cli.bench_bad_input]=] "bash" "/work/main/tests/cli/bench_bad_input.sh")
set_tests_properties([=[cli.bench_bad_input]=] PROPERTIES  ENVIRONMENT "CALBENCH=/work/main/build/calbench;SRC=/work/main;SHARED=/work/main/../shared" LABELS "cli" _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;33;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[cli.bench_foreign_recording]=] "bash" "/work/main/tests/cli/bench_foreign_recording.sh")
set_tests_properties([=[cli.bench_foreign_recording]=] PROPERTIES  ENVIRONMENT "CALBENCH=/work/main/build/calbench;SRC=/work/main;SHARED=/work/main/../shared" LABELS "cli" _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;33;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[cli.bench_simulate_fit]=] "bash" "/work/main/tests/cli/bench_simulate_fit.sh")
set_tests_properties([=[cli.bench_simulate_fit]=] PROPERTIES  ENVIRONMENT "CALBENCH=/work/main/build/calbench;SRC=/work/main;SHARED=/work/main/../shared" LABELS "cli" _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;33;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[cli.db_concurrency]=] "bash" "/work/main/tests/cli/db_concurrency.sh")
set_tests_properties([=[cli.db_concurrency]=] PROPERTIES  ENVIRONMENT "CALBENCH=/work/main/build/calbench;SRC=/work/main;SHARED=/work/main/../shared" LABELS "cli" _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;33;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[cli.db_import_inmotion]=] "bash" "/work/main/tests/cli/db_import_inmotion.sh")
set_tests_properties([=[cli.db_import_inmotion]=] PROPERTIES  ENVIRONMENT "CALBENCH=/work/main/build/calbench;SRC=/work/main;SHARED=/work/main/../shared" LABELS "cli" _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;33;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[cli.db_provision]=] "bash" "/work/main/tests/cli/db_provision.sh")
set_tests_properties([=[cli.db_provision]=] PROPERTIES  ENVIRONMENT "CALBENCH=/work/main/build/calbench;SRC=/work/main;SHARED=/work/main/../shared" LABELS "cli" _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;33;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[cli.db_report_browser]=] "bash" "/work/main/tests/cli/db_report_browser.sh")
set_tests_properties([=[cli.db_report_browser]=] PROPERTIES  ENVIRONMENT "CALBENCH=/work/main/build/calbench;SRC=/work/main;SHARED=/work/main/../shared" LABELS "cli" _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;33;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[cli.db_workflow]=] "bash" "/work/main/tests/cli/db_workflow.sh")
set_tests_properties([=[cli.db_workflow]=] PROPERTIES  ENVIRONMENT "CALBENCH=/work/main/build/calbench;SRC=/work/main;SHARED=/work/main/../shared" LABELS "cli" _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;33;add_test;/work/main/tests/CMakeLists.txt;0;")
add_test([=[cli.devices_emulate]=] "bash" "/work/main/tests/cli/devices_emulate.sh")
set_tests_properties([=[cli.devices_emulate]=] PROPERTIES  ENVIRONMENT "CALBENCH=/work/main/build/calbench;SRC=/work/main;SHARED=/work/main/../shared" LABELS "cli" _BACKTRACE_TRIPLES "/work/main/tests/CMakeLists.txt;33;add_test;/work/main/tests/CMakeLists.txt;0;")
