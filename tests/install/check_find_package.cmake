# CTest Install.find_package (packaging/CMakeLists.txt): find_package(dpc31emu) from a fresh
# prefix, with tests/install/find_package as the consumer.
#  - A required component that cannot be had fails with dpc31emu_NOT_FOUND_MESSAGE naming it: an
#    unknown one; systemc without SystemC's pkg-config module (PKG_CONFIG_LIBDIR emptied, as on a
#    machine without libsystemc-dev), or in an installation built without SystemC.
#  - The consumer, which sets no C++ standard, builds on dpc31emu::emu (cxx_std_20 comes with it).
#  - Its C++ and C programs print the version macros and dpc31emu_version(): each is the
#    project's version (project(VERSION), passed as VERSION).
#   cmake -DBUILD_DIR=... -DWORK_DIR=... -DCONSUMER_DIR=... -DVERSION=... -DSYSTEMC=ON|OFF
#         -DC_COMPILER=... -DCXX_COMPILER=... -P check_find_package.cmake
include(${CMAKE_CURRENT_LIST_DIR}/../../packaging/install_test_common.cmake)

# Configures the consumer with COMPONENTS `component`; it must fail and say `want` (CMake wraps
# the message's lines: compared with the white space collapsed).
function(refused component want)
  execute_process(COMMAND ${CMAKE_COMMAND} -S ${CONSUMER_DIR} -B ${WORK_DIR}/${component}
    -DCMAKE_PREFIX_PATH=${prefix} "-DDPC31EMU_COMPONENTS=COMPONENTS;${component}"
    RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
  string(REGEX REPLACE "[ \n]+" " " flat "${err}")
  string(FIND "${flat}" "${want}" at)
  if(rc EQUAL 0 OR at EQUAL -1)
    message(FATAL_ERROR "COMPONENTS ${component}: exit ${rc}, want a failure saying '${want}', "
                        "got:\n${err}")
  endif()
endfunction()

refused(bogus "unknown component \"bogus\" (the one component is systemc)")
if(SYSTEMC)
  set(ENV{PKG_CONFIG_LIBDIR} ${WORK_DIR}/no-pkgconfig)
  string(CONCAT want "component systemc needs SystemC, which pkg-config did not find as module "
         "\"systemc\" (Debian: install libsystemc-dev)")
  refused(systemc "${want}")
  unset(ENV{PKG_CONFIG_LIBDIR})
else()
  string(CONCAT want "component systemc: this installation has no SystemC model (it was built "
         "without SystemC, Debian's libsystemc-dev)")
  refused(systemc "${want}")
endif()

run(${CMAKE_COMMAND} -S ${CONSUMER_DIR} -B ${WORK_DIR}/build -DCMAKE_PREFIX_PATH=${prefix}
  -DCMAKE_C_COMPILER=${C_COMPILER} -DCMAKE_CXX_COMPILER=${CXX_COMPILER})
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
foreach(program version_cpp version_c)
  run(${WORK_DIR}/build/${program})
  if(NOT out STREQUAL "${VERSION} ${VERSION} ${VERSION}\n")
    message(FATAL_ERROR "${program}: got '${out}', want '${VERSION} ${VERSION} ${VERSION}'")
  endif()
endforeach()
