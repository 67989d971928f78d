# CTest Install.systemc (examples/systemc/CMakeLists.txt): installs the build into a fresh prefix,
# builds examples/systemc with only that prefix on CMAKE_PREFIX_PATH
# (find_package(dpc31emu COMPONENTS systemc)) and runs it: the virtual platform reaches
# Data_Exchange with the native run's cycles. Any failing step fails the test.
#   cmake -DBUILD_DIR=... -DWORK_DIR=... -DEXAMPLE_DIR=... -DCXX_COMPILER=... -P check_install.cmake
include(${CMAKE_CURRENT_LIST_DIR}/../packaging/install_test_common.cmake)
foreach(f include/dpc31/systemc/dpc31_tlm.hpp)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
run(${CMAKE_COMMAND} -S ${EXAMPLE_DIR} -B ${WORK_DIR}/build -DCMAKE_PREFIX_PATH=${prefix}
  -DCMAKE_CXX_COMPILER=${CXX_COMPILER} -DCMAKE_BUILD_TYPE=Release
  "-DCMAKE_CXX_FLAGS=-Wall -Wextra -Werror")
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run(${WORK_DIR}/build/dpc31_vp_do4)
