# CTest Install.cosim_rtl (packaging/CMakeLists.txt): the Done-when of `dpc31 cosim --rtl`
# (docs/golden-model.md) from an installed prefix. Installs the build into a fresh prefix, then,
# with only that prefix's files: our Verilog passed as --rtl is clean over 200 seeds, a mutant of
# it (--define MUTANTS --mutant NO_C_SWAP) is caught (exit 1), both built from the prefix's
# adapter (checked in the generated project), and examples/rtl_model builds a model with
# find_package(dpc31emu) and dpc31emu_verilate_model() that `dpc31 cosim --rtl-model` runs clean.
# The prefix is moved after the install (issue 29: relocatable, never reading the build tree):
# the installed dpc31, stripped as the Debian package is, holds no path of the source or build
# tree, and everything above runs from the moved prefix.
#   cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... -DEXAMPLE_DIR=... -DCXX_COMPILER=...
#     -P check_install_rtl.cmake
set(prefix ${WORK_DIR}/prefix)
set(cache ${WORK_DIR}/cache)
file(REMOVE_RECURSE ${WORK_DIR})

function(run)
  execute_process(COMMAND ${ARGN} COMMAND_ECHO STDOUT COMMAND_ERROR_IS_FATAL ANY)
endfunction()

run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/installed-here --strip)
file(RENAME ${WORK_DIR}/installed-here ${prefix})
foreach(tree ${SOURCE_DIR} ${BUILD_DIR})
  file(STRINGS ${prefix}/bin/dpc31 hits REGEX "${tree}")
  if(hits)
    list(GET hits 0 hit)
    message(FATAL_ERROR "the installed dpc31 names ${tree}: ${hit}")
  endif()
endforeach()
set(share ${prefix}/share/dpc31emu)
foreach(f cosim/dpc31emu_rtl.cmake cosim/rtl_model_entry.cpp cosim/verilated_blocks.hpp
    cosim/dpc31_rtl_model.h rtl/dpc31_blocks.v rtl/dpc31_blocks_actions.vh
    rtl/dpc31_blocks_constants.vh rtl/dpc31_regs.vh)
  if(NOT EXISTS ${share}/${f})
    message(FATAL_ERROR "not installed: share/dpc31emu/${f}")
  endif()
endforeach()

set(ENV{DPC31EMU_RTL_CACHE} ${cache})
set(rtl --rtl ${share}/rtl/dpc31_blocks.v --top dpc31_blocks --seeds 200 --quiet)
run(${prefix}/bin/dpc31 cosim ${rtl} OUTPUT_FILE ${WORK_DIR}/clean.json)
execute_process(COMMAND ${prefix}/bin/dpc31 cosim ${rtl} --define MUTANTS --mutant NO_C_SWAP
  --out ${WORK_DIR}/mutant RESULT_VARIABLE rc OUTPUT_FILE ${WORK_DIR}/mutant.json)
if(NOT rc EQUAL 1)
  message(FATAL_ERROR "the mutant NO_C_SWAP as --rtl: exit ${rc}, want 1 (caught)")
endif()
file(GLOB projects ${cache}/*/project/CMakeLists.txt)
list(LENGTH projects n)
if(NOT n EQUAL 2)
  message(FATAL_ERROR "${n} models in the cache, want 2")
endif()
# The generated projects name no path: the installed function's comes as a -D value (data).
foreach(p IN LISTS projects)
  file(READ ${p} text)
  string(FIND "${text}" "include(\"\${DPC31_RTL_CMAKE}\")" at)
  string(FIND "${text}" "${WORK_DIR}" slash)
  if(at LESS 0 OR NOT slash LESS 0)
    message(FATAL_ERROR "${p}: not the fixed project text")
  endif()
endforeach()

# The function in a project of one's own, found through the package.
run(${CMAKE_COMMAND} -S ${EXAMPLE_DIR} -B ${WORK_DIR}/build -DCMAKE_PREFIX_PATH=${prefix}
  -DCMAKE_CXX_COMPILER=${CXX_COMPILER} -DCMAKE_BUILD_TYPE=RelWithDebInfo)
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build --parallel 2)
run(${prefix}/bin/dpc31 cosim --rtl-model ${WORK_DIR}/build/my_blocks.so --seeds 20 --quiet
  OUTPUT_FILE ${WORK_DIR}/model.json)
