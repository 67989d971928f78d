# CTest Install.consumer (packaging/CMakeLists.txt): installs the build into a fresh prefix,
# checks the installed files, runs the installed CLI, builds examples/consumer with only that
# prefix on CMAKE_PREFIX_PATH and runs it (the segment consumer's VCD and pcapng checked),
# compiles every installed header alone, docs/cpu.md's 80C32 snippet and README's "Using the
# library" snippet (tests/install/headers), and builds and runs its C program and
# tests/install/pkgconfig_consumer.cpp (C++: the 80C32 board, the segment outputs) through
# pkg-config alone. Then examples/plugin the same way: its firmware plug-in in both
# configurations (interrupt-driven, and polling with every interrupt masked) under its C host,
# and behind the installed `dpc31 bridge` with the installed tools/dp_master.py as the master, to
# Data_Exchange; the plug-in built with pkg-config's flags alone; the driver's fatal-error loop
# stopped by the hang guard (bridge_example.py). Any failing step fails the test.
#   cmake -DBUILD_DIR=... -DWORK_DIR=... -DEXAMPLE_DIR=... -DPLUGIN_DIR=... -DBRIDGE_CHECK=...
#         -DHEADERS_DIR=... -DCPU_DOC=... -DREADME=... -DPKGCONFIG_CONSUMER=... -DPYTHON=...
#         -DLIBDIR=... -DC_COMPILER=... -DCXX_COMPILER=... -P check_install.cmake
set(prefix ${WORK_DIR}/prefix)
file(REMOVE_RECURSE ${WORK_DIR})

function(run)
  execute_process(COMMAND ${ARGN} COMMAND_ECHO STDOUT COMMAND_ERROR_IS_FATAL ANY)
endfunction()

run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})

foreach(f bin/dpc31 include/dpc31/chip.hpp include/dpc31/dpc31_hal.h include/dpc31/dpc31_regs.h
    include/dpc31/dpc31_pdu.h
    include/dpc31/reg_ids.hpp include/dpc31/reg_fields.hpp include/dpc31/session/scenario.hpp
    include/dpc31/firmware/firmware.h include/dpc31/dpc31_firmware.h include/mcs51/cpu.hpp
    include/mcs51/ihex.hpp include/dpc31/session/cpu51_board.hpp ${LIBDIR}/libdpc31emu.so
    ${LIBDIR}/libdpc31emu_segment_outputs.so include/dpc31/segment_outputs/segment_outputs.hpp
    ${LIBDIR}/dpc31emu/libdpc31_fw_do4.so ${LIBDIR}/dpc31emu/libdpc31_fw_cnt2.so
    share/dpc31emu/tools/dp_master.py
    ${LIBDIR}/cmake/dpc31emu/dpc31emuConfig.cmake
    ${LIBDIR}/cmake/dpc31emu/dpc31emuConfigVersion.cmake ${LIBDIR}/pkgconfig/dpc31emu.pc
    share/dpc31emu/firmware/do4/DO4_0D04.gsd share/dpc31emu/firmware/cnt2/CNT2_0C02.gsd
    share/dpc31emu/wireshark/profibus_dl.lua
    share/dpc31emu/sigrok/profibus_dp/__init__.py share/dpc31emu/sigrok/profibus_dp/pd.py
    share/dpc31emu/gtkwave/dp_state.txt share/dpc31emu/gtkwave/buffer_sm.txt share/doc/dpc31emu/README.md
    share/doc/dpc31emu/install.md)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()

run(${prefix}/bin/dpc31 demo --out-dir ${WORK_DIR}/demo)

# Our examples build warning-free, as in a user's tree that turns warnings into errors (GCC 14
# makes -Wint-conversion one by default).
set(strict "-Wall -Wextra -Werror")

# The CMake package: only the prefix.
run(${CMAKE_COMMAND} -S ${EXAMPLE_DIR} -B ${WORK_DIR}/build -DCMAKE_PREFIX_PATH=${prefix}
  -DCMAKE_C_COMPILER=${C_COMPILER} -DCMAKE_CXX_COMPILER=${CXX_COMPILER}
  -DCMAKE_BUILD_TYPE=Release "-DCMAKE_C_FLAGS=${strict}" "-DCMAKE_CXX_FLAGS=${strict}")
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run(${WORK_DIR}/build/session_consumer)
# dpc31emu::segment_outputs: a segment's VCD (a scope per station) and the pcapng of its line.
run(${WORK_DIR}/build/segment_consumer ${WORK_DIR}/segment.vcd ${WORK_DIR}/segment.pcapng)
file(READ ${WORK_DIR}/segment.vcd vcd)
foreach(scope station5_spc3 station6_vpc3plus)
  string(FIND "${vcd}" "$scope module ${scope} $end" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "segment.vcd has no scope ${scope}")
  endif()
endforeach()
file(READ ${WORK_DIR}/segment.pcapng shb LIMIT 4 HEX)
if(NOT shb STREQUAL "0a0d0d0a")
  message(FATAL_ERROR "segment.pcapng does not begin with a Section Header Block: ${shb}")
endif()
run(${WORK_DIR}/build/hal_consumer)

# Every installed header alone, docs/cpu.md's 80C32 snippet and README's snippet as written
# (tests/install/headers).
run(${CMAKE_COMMAND} -S ${HEADERS_DIR} -B ${WORK_DIR}/headers -DCMAKE_PREFIX_PATH=${prefix}
  -DDPC31_PREFIX=${prefix} -DCPU_DOC=${CPU_DOC} -DREADME=${README} -DCMAKE_C_COMPILER=${C_COMPILER}
  -DCMAKE_CXX_COMPILER=${CXX_COMPILER} "-DCMAKE_C_FLAGS=${strict}" "-DCMAKE_CXX_FLAGS=${strict}")
run(${CMAKE_COMMAND} --build ${WORK_DIR}/headers --parallel 2)
# README's program: three bus accesses of 4 clocks, then step(48000) (docs/timing.md).
execute_process(COMMAND ${WORK_DIR}/headers/readme_snippet OUTPUT_VARIABLE readme_out
  COMMAND_ECHO STDOUT COMMAND_ERROR_IS_FATAL ANY)
if(NOT readme_out MATCHES ", cycle 48012\n$")
  message(FATAL_ERROR "README's snippet: got '${readme_out}', want its last line to end 'cycle 48012'")
endif()

# pkg-config: only the prefix's .pc files; a plain C compile and link.
set(ENV{PKG_CONFIG_LIBDIR} ${prefix}/${LIBDIR}/pkgconfig)
execute_process(COMMAND pkg-config --cflags --libs dpc31emu OUTPUT_VARIABLE flags
  OUTPUT_STRIP_TRAILING_WHITESPACE COMMAND_ECHO STDOUT COMMAND_ERROR_IS_FATAL ANY)
message(STATUS "pkg-config: ${flags}")
separate_arguments(flags UNIX_COMMAND "${flags}")
run(${C_COMPILER} -std=c99 -Wall -Wextra -Werror ${EXAMPLE_DIR}/hal_consumer.c ${flags}
  -o ${WORK_DIR}/hal_pkgconfig)
# A C++ program on the 80C32 board by name and the segment outputs, from the same flags alone.
run(${CXX_COMPILER} -std=c++20 -Wall -Wextra -Werror ${PKGCONFIG_CONSUMER} ${flags}
  -o ${WORK_DIR}/cpp_pkgconfig)
set(ENV{LD_LIBRARY_PATH} ${prefix}/${LIBDIR})
run(${WORK_DIR}/hal_pkgconfig)
# SJMP $ for 1 ms of the chip at 48 MHz: the 80C32 at 24 MHz, 12 clocks a machine cycle, has run
# 48000 / 24 = 2000 machine cycles (docs/timing.md, "An 80C32 beside the chip") and stays at 0000h.
execute_process(COMMAND ${WORK_DIR}/cpp_pkgconfig OUTPUT_VARIABLE cpp_out COMMAND_ECHO STDOUT
  COMMAND_ERROR_IS_FATAL ANY)
set(want "pkgconfig consumer: station5_spc3, PC 0000h after 2000 machine cycles\n")
if(NOT cpp_out STREQUAL want)
  message(FATAL_ERROR "cpp_pkgconfig: got '${cpp_out}', want '${want}'")
endif()

# examples/plugin: the plug-ins and the C host, from the CMake package only.
unset(ENV{LD_LIBRARY_PATH})
run(${CMAKE_COMMAND} -S ${PLUGIN_DIR} -B ${WORK_DIR}/plugin -DCMAKE_PREFIX_PATH=${prefix}
  -DCMAKE_C_COMPILER=${C_COMPILER} -DCMAKE_BUILD_TYPE=Release "-DCMAKE_C_FLAGS=${strict}")
run(${CMAKE_COMMAND} --build ${WORK_DIR}/plugin)
foreach(plugin example example_polling)
  execute_process(COMMAND ${WORK_DIR}/plugin/example_host ${WORK_DIR}/plugin/lib${plugin}.so
    OUTPUT_VARIABLE host_out COMMAND_ECHO STDOUT COMMAND_ERROR_IS_FATAL ANY)
  message(STATUS "${host_out}")
  # 150 ms of chip time after init; started, waiting for its parameters (Wait_Prm). The
  # interrupt-driven one's main loop turned its LED on after 100 ms; the polling one has no LED
  # loop (the port keeps its power-on 0).
  if(plugin STREQUAL "example")
    set(want "EXAMPLE on vpc3plus: 150 ms after init, started 1, DP state 0, led 1")
  else()
    set(want "EXAMPLE-POLLING on vpc3plus: 150 ms after init, started 1, DP state 0, led 0")
  endif()
  if(NOT host_out STREQUAL "${want}\n")
    message(FATAL_ERROR "example_host ${plugin}: got '${host_out}', want '${want}'")
  endif()
  foreach(case dx fatal)
    run(${PYTHON} ${BRIDGE_CHECK} ${prefix}/bin/dpc31 ${prefix}/share/dpc31emu/tools/dp_master.py
      ${WORK_DIR}/plugin/lib${plugin}.so ${case})
  endforeach()
endforeach()

# A plug-in from pkg-config's flags alone (no library: the host provides the symbols).
set(ENV{PKG_CONFIG_LIBDIR} ${prefix}/${LIBDIR}/pkgconfig)
execute_process(COMMAND pkg-config --cflags dpc31emu OUTPUT_VARIABLE cflags
  OUTPUT_STRIP_TRAILING_WHITESPACE COMMAND_ERROR_IS_FATAL ANY)
separate_arguments(cflags UNIX_COMMAND "${cflags}")
run(${C_COMPILER} -std=c99 -shared -fPIC -fvisibility=hidden -DDP_POLLING ${cflags}
  ${PLUGIN_DIR}/example.c ${PLUGIN_DIR}/dp_slave.c -o ${WORK_DIR}/libexample_pc.so)
run(${PYTHON} ${BRIDGE_CHECK} ${prefix}/bin/dpc31 ${prefix}/share/dpc31emu/tools/dp_master.py
  ${WORK_DIR}/libexample_pc.so dx)
