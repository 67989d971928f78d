# CTest Install.python (python/CMakeLists.txt): the dpc31 package installed the Debian way.
# `cmake --install` into a fresh prefix puts it in lib/python3/dist-packages/dpc31 (no
# LD_LIBRARY_PATH: the module finds libdpc31emu.so by its RPATH); the system python3 imports it
# from there and runs issue 32's command and a firmware plug-in from the prefix to
# Data_Exchange, and prints dpc31.__version__. Then the .deb's layout: what `cpack -G DEB` packs
# is this install with the prefix /usr (CPACK_PACKAGING_INSTALL_PREFIX), so an install to DESTDIR
# with --prefix /usr must put the module where Debian's python3 looks
# (/usr/lib/python3/dist-packages) and work from there. -DDEB=ON also builds the .deb and looks
# into it (minutes: not in CTest). Any failing
# step fails the test.
#   cmake -DBUILD_DIR=... -DWORK_DIR=... -DPYTHON=... -DLIBDIR=... -DVERSION=... -DDEB=ON|OFF
#         -P check_install.cmake
include(${CMAKE_CURRENT_LIST_DIR}/../packaging/install_test_common.cmake)
set(site ${prefix}/lib/python3/dist-packages)
foreach(f dpc31/__init__.py dpc31/__init__.pyi dpc31/client.py dpc31/py.typed)
  if(NOT EXISTS ${site}/${f})
    message(FATAL_ERROR "not installed: lib/python3/dist-packages/${f}")
  endif()
endforeach()

unset(ENV{LD_LIBRARY_PATH})
set(ENV{PYTHONPATH} ${site})
# (Semicolons would split a CMake argument: the command's lines go through a file.)
file(WRITE ${WORK_DIR}/done_when.py "import dpc31\nc = dpc31.Chip('spc3')\nc.write(0x04, 0xFF)\nc.step(48000)\nprint(c.cycle)\n")
run(${PYTHON} ${WORK_DIR}/done_when.py)
if(NOT out STREQUAL "48004\n")
  message(FATAL_ERROR "issue 32's command printed '${out}', expected 48004 (one access of 4 clocks + 48000)")
endif()
file(WRITE ${WORK_DIR}/plugin.py "import dpc31
m = dpc31.Master(dpc31.Chip('dpc31'))
fw = m.run_firmware('${prefix}/${LIBDIR}/dpc31emu/libdpc31_fw_do4.so')
assert m.startup(), 'no Data_Exchange'
print(dpc31.__file__, fw.name, m.chip.dp_state.name)
")
run(${PYTHON} ${WORK_DIR}/plugin.py)
if(NOT out MATCHES "^${site}/dpc31/__init__.py DO4 Data_Exchange\n$")
  message(FATAL_ERROR "the installed module with the installed DO4 plug-in printed '${out}'")
endif()

# dpc31.__version__: the loaded libdpc31emu.so's, the project's version (project(VERSION)).
file(WRITE ${WORK_DIR}/version.py "import dpc31\nprint(dpc31.__version__)\n")
run(${PYTHON} ${WORK_DIR}/version.py)
if(NOT out STREQUAL "${VERSION}\n")
  message(FATAL_ERROR "dpc31.__version__ is '${out}', want '${VERSION}'")
endif()

set(ENV{DESTDIR} ${WORK_DIR}/root)
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix /usr)
unset(ENV{DESTDIR})
set(ENV{PYTHONPATH} ${WORK_DIR}/root/usr/lib/python3/dist-packages)
run(${PYTHON} ${WORK_DIR}/done_when.py)
if(NOT out STREQUAL "48004\n")
  message(FATAL_ERROR "from DESTDIR/usr/lib/python3/dist-packages: printed '${out}'")
endif()

if(DEB)
  run(cpack -G DEB -B ${WORK_DIR}/deb --config ${BUILD_DIR}/CPackConfig.cmake)
  file(GLOB deb ${WORK_DIR}/deb/dpc31emu_*.deb)
  run(dpkg-deb -c ${deb})
  execute_process(COMMAND ${PYTHON} -c "import sysconfig; print(sysconfig.get_config_var('EXT_SUFFIX'))"
    OUTPUT_VARIABLE suffix OUTPUT_STRIP_TRAILING_WHITESPACE)
  foreach(f __init__.py __init__.pyi client.py _dpc31${suffix})
    if(NOT out MATCHES "./usr/lib/python3/dist-packages/dpc31/${f}\n")
      message(FATAL_ERROR "the .deb has no /usr/lib/python3/dist-packages/dpc31/${f}")
    endif()
  endforeach()
endif()
