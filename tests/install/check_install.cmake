# CTest Install.consumer (packaging/CMakeLists.txt): installs the build into a fresh prefix,
# checks the installed files, runs the installed CLI, builds examples/consumer with only that
# prefix on CMAKE_PREFIX_PATH and runs it, and builds and runs its C program through
# pkg-config. Any failing step fails the test.
#   cmake -DBUILD_DIR=... -DWORK_DIR=... -DEXAMPLE_DIR=... -DLIBDIR=... -DC_COMPILER=...
#         -DCXX_COMPILER=... -P check_install.cmake
set(prefix ${WORK_DIR}/prefix)
file(REMOVE_RECURSE ${WORK_DIR})

function(run)
  execute_process(COMMAND ${ARGN} COMMAND_ECHO STDOUT COMMAND_ERROR_IS_FATAL ANY)
endfunction()

run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})

foreach(f bin/dpc31 include/dpc31/chip.hpp include/dpc31/dpc31_hal.h include/dpc31/dpc31_regs.h
    include/dpc31/reg_ids.hpp include/dpc31/reg_fields.hpp include/dpc31/session/scenario.hpp
    include/dpc31/firmware/firmware.h ${LIBDIR}/libdpc31emu.so
    ${LIBDIR}/cmake/dpc31emu/dpc31emuConfig.cmake
    ${LIBDIR}/cmake/dpc31emu/dpc31emuConfigVersion.cmake ${LIBDIR}/pkgconfig/dpc31emu.pc
    share/dpc31emu/firmware/do4/DO4_0D04.gsd share/dpc31emu/firmware/cnt2/CNT2_0C02.gsd
    share/dpc31emu/wireshark/profibus_dl.lua share/doc/dpc31emu/README.md
    share/doc/dpc31emu/install.md)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()

run(${prefix}/bin/dpc31 demo --out-dir ${WORK_DIR}/demo)

# The CMake package: only the prefix.
run(${CMAKE_COMMAND} -S ${EXAMPLE_DIR} -B ${WORK_DIR}/build -DCMAKE_PREFIX_PATH=${prefix}
  -DCMAKE_C_COMPILER=${C_COMPILER} -DCMAKE_CXX_COMPILER=${CXX_COMPILER}
  -DCMAKE_BUILD_TYPE=Release)
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run(${WORK_DIR}/build/session_consumer)
run(${WORK_DIR}/build/hal_consumer)

# pkg-config: only the prefix's .pc files; a plain C compile and link.
set(ENV{PKG_CONFIG_LIBDIR} ${prefix}/${LIBDIR}/pkgconfig)
execute_process(COMMAND pkg-config --cflags --libs dpc31emu OUTPUT_VARIABLE flags
  OUTPUT_STRIP_TRAILING_WHITESPACE COMMAND_ECHO STDOUT COMMAND_ERROR_IS_FATAL ANY)
message(STATUS "pkg-config: ${flags}")
separate_arguments(flags UNIX_COMMAND "${flags}")
run(${C_COMPILER} -std=c99 ${EXAMPLE_DIR}/hal_consumer.c ${flags} -o ${WORK_DIR}/hal_pkgconfig)
set(ENV{LD_LIBRARY_PATH} ${prefix}/${LIBDIR})
run(${WORK_DIR}/hal_pkgconfig)
