# dpc31emu_verilate_model(): your RTL as a model for the lockstep harness (docs/golden-model.md,
# "Putting your own RTL under the harness"). Installed with the CMake package
# (find_package(dpc31emu) includes it); `dpc31 cosim --rtl` builds through the same function.
#
#   dpc31emu_verilate_model(TARGET my_model SOURCES my_blocks.v [more.v ...] TOP my_blocks
#     [PROFILE spc3|vpc3plus|dpc31] [DEFINES NAME[=VALUE] ...] [INCLUDE_DIRS dir ...])
#
# makes the module library my_model.so (no "lib" prefix), which `dpc31 cosim --rtl-model
# my_model.so` loads. Verilator runs with the flags of our own models (rtl/CMakeLists.txt):
# -Wall (a lint warning stops the build), -GPROFILE=<0 spc3, 1 vpc3plus, 2 dpc31>, -I for each
# source's directory and INCLUDE_DIRS, -D for DEFINES, FST tracing compiled in. The top module's
# ports are checked against the harness's list below right after Verilator and again at every
# build: a port missing or of the wrong width is one line, "dpc31emu: ...".
#
# Run as a script, the file checks one Verilated header:
#   cmake -DDPC31EMU_CHECK_HEADER=Vtop.h -DDPC31EMU_CHECK_STAMP=stamp -P dpc31emu_rtl.cmake
include_guard(GLOBAL)

# The ports of docs/golden-model.md: direction, name, width. mutant_sel is optional.
set(_dpc31emu_rtl_ports
  "IN clk 1" "IN rst 1" "IN motorola 1" "IN asic_type 4" "IN bus_addr 13" "IN bus_wdata 8"
  "IN bus_rd 1" "IN bus_wr 1" "IN ev_irq 16" "IN ev_leave_master 1" "IN ev_wd_expired 1" "IN ev_gc 1" "IN gc_cmd 8"
  "IN ev_dout 1" "IN ev_failsafe 1" "IN ev_din 1" "IN ev_diag_begin 1" "IN ev_diag_end 1"
  "IN stat_diag 1" "IN ev_prm 1" "IN ev_cfg 1" "IN ev_ssa 1" "IN ev_prm_fault 1" "IN ev_dx 1"
  "IN ev_dis 1" "IN dis_bits 2" "IN ev_mac_stop 1" "IN ev_mac_start 1"
  "IN ev_ext_prm 1" "IN ev_sap_sent 1" "IN ev_sap_ind 1" "IN ev_sap_srd 1" "IN sap_entry 13"
  "IN sap_len 8"
  "OUT x_int 1" "OUT irr 16" "OUT imr 16" "OUT mode_reg0 16" "OUT mode_reg1 8" "OUT started 1"
  "OUT dp_state 2" "OUT prm_pending 1" "OUT cfg_pending 1" "OUT ssa_free 1" "OUT prm_fault 1"
  "OUT cfg_fault 1" "OUT not_supported 1" "OUT sync_mode 1" "OUT freeze_mode 1"
  "OUT diag_flag 1" "OUT dout_sm 8" "OUT din_sm 8" "OUT diag_sm 4" "OUT u_cleared 1"
  "OUT n_cleared 1" "OUT n_cl 1" "OUT d_fresh 1" "OUT dout_ptr1 8" "OUT dout_ptr2 8"
  "OUT dout_ptr3 8" "OUT dout_ptr_c 8" "OUT cfg_ptr 8" "OUT read_cfg_ptr 8" "OUT gc_command 8"
  "OUT bus_rdata 8")
set(_dpc31emu_rtl_optional_ports "IN mutant_sel 4")

# One line on stderr as it is (FATAL_ERROR's own text is reflowed), then the stop.
function(_dpc31emu_fail)
  string(CONCAT text ${ARGN})
  message(NOTICE "dpc31emu: ${text}")
  message(FATAL_ERROR "dpc31emu_verilate_model stopped (the line above)")
endfunction()

# Fails with one line if the Verilated header's ports do not match the list: each listed port
# present with its direction and width, no other input (the harness would leave it at 0).
function(_dpc31emu_check_ports header)
  file(STRINGS "${header}" lines REGEX "VL_(IN|OUT|INOUT)[0-9W]*\\(&")
  get_filename_component(model "${header}" NAME_WE)
  set(seen "")
  foreach(line IN LISTS lines)
    if(NOT line MATCHES "VL_(IN|OUT|INOUT)[0-9W]*\\(&([A-Za-z0-9_]+),([0-9]+),([0-9]+)")
      continue()
    endif()
    set(dir ${CMAKE_MATCH_1})
    set(name ${CMAKE_MATCH_2})
    math(EXPR width "${CMAKE_MATCH_3} - ${CMAKE_MATCH_4} + 1")
    set(want "")
    foreach(p IN LISTS _dpc31emu_rtl_ports _dpc31emu_rtl_optional_ports)
      separate_arguments(p)
      list(GET p 1 pname)
      if(pname STREQUAL name)
        set(want ${p})
      endif()
    endforeach()
    if(NOT want)
      if(NOT dir STREQUAL "OUT")
        _dpc31emu_fail("${model}: port ${name} is not one of the harness's inputs "
          "(docs/golden-model.md lists them, and nothing would drive it)")
      endif()
      continue()  # an extra output is not compared
    endif()
    list(GET want 0 wdir)
    list(GET want 2 wwidth)
    if(NOT dir STREQUAL wdir OR NOT width EQUAL wwidth)
      string(TOLOWER "${dir}" d)
      string(TOLOWER "${wdir}" wd)
      _dpc31emu_fail("${model}: port ${name} is a ${width}-bit ${d}put, the "
        "harness needs a ${wwidth}-bit ${wd}put (docs/golden-model.md)")
    endif()
    list(APPEND seen ${name})
  endforeach()
  foreach(p IN LISTS _dpc31emu_rtl_ports)
    separate_arguments(p)
    list(GET p 1 pname)
    list(FIND seen ${pname} at)
    if(at LESS 0)
      list(GET p 0 wdir)
      list(GET p 2 wwidth)
      string(TOLOWER "${wdir}" wd)
      _dpc31emu_fail("${model}: port ${pname} missing (a ${wwidth}-bit ${wd}put, "
        "docs/golden-model.md)")
    endif()
  endforeach()
endfunction()

if(CMAKE_SCRIPT_MODE_FILE AND DPC31EMU_CHECK_HEADER)
  _dpc31emu_check_ports("${DPC31EMU_CHECK_HEADER}")
  file(TOUCH "${DPC31EMU_CHECK_STAMP}")
  return()
endif()

set(_dpc31emu_rtl_file "${CMAKE_CURRENT_LIST_FILE}")
if(NOT DPC31EMU_RTL_ADAPTER_DIR)
  # Installed: the adapter sits next to this file (share/dpc31emu/cosim).
  set(DPC31EMU_RTL_ADAPTER_DIR "${CMAKE_CURRENT_LIST_DIR}")
endif()

function(dpc31emu_verilate_model)
  cmake_parse_arguments(PARSE_ARGV 0 arg "" "TARGET;TOP;PROFILE" "SOURCES;DEFINES;INCLUDE_DIRS")
  if(NOT arg_TARGET OR NOT arg_TOP OR NOT arg_SOURCES)
    _dpc31emu_fail("dpc31emu_verilate_model needs TARGET, SOURCES and TOP")
  endif()
  if(NOT arg_PROFILE)
    set(arg_PROFILE dpc31)
  endif()
  set(profiles spc3 vpc3plus dpc31)
  list(FIND profiles "${arg_PROFILE}" profile_index)
  if(profile_index LESS 0)
    _dpc31emu_fail("PROFILE ${arg_PROFILE}: not spc3, vpc3plus or dpc31")
  endif()
  # Here, not once at include time: verilate() needs the package's variables in this scope.
  find_package(verilator REQUIRED HINTS $ENV{VERILATOR_ROOT} /usr/share/verilator)
  set(args -Wall -GPROFILE=${profile_index})
  set(sources "")
  foreach(s IN LISTS arg_SOURCES)
    get_filename_component(s "${s}" ABSOLUTE)
    get_filename_component(d "${s}" DIRECTORY)
    list(APPEND sources "${s}")
    list(APPEND args "-I${d}")
  endforeach()
  foreach(d IN LISTS arg_INCLUDE_DIRS)
    get_filename_component(d "${d}" ABSOLUTE)
    list(APPEND args "-I${d}")
  endforeach()
  list(REMOVE_DUPLICATES args)
  foreach(d IN LISTS arg_DEFINES)
    list(APPEND args "-D${d}")
  endforeach()

  set(prefix V${arg_TOP})
  set(vdir ${CMAKE_CURRENT_BINARY_DIR}/${arg_TARGET}.verilator)
  # The entry point as a source of this target alone, so its dependency on the port check is
  # this target's.
  set(entry ${CMAKE_CURRENT_BINARY_DIR}/${arg_TARGET}_entry.cpp)
  file(CONFIGURE OUTPUT ${entry}
    CONTENT "#include \"${DPC31EMU_RTL_ADAPTER_DIR}/rtl_model_entry.cpp\"\n")
  add_library(${arg_TARGET} MODULE ${entry})
  verilate(${arg_TARGET} SOURCES ${sources} PREFIX ${prefix} TOP_MODULE ${arg_TOP} TRACE_FST
    DIRECTORY ${vdir} VERILATOR_ARGS ${args})
  _dpc31emu_check_ports(${vdir}/${prefix}.h)  # a fresh configure: before any compile
  add_custom_command(OUTPUT ${vdir}/ports.checked
    COMMAND ${CMAKE_COMMAND} -DDPC31EMU_CHECK_HEADER=${vdir}/${prefix}.h
      -DDPC31EMU_CHECK_STAMP=${vdir}/ports.checked -P ${_dpc31emu_rtl_file}
    DEPENDS ${vdir}/${prefix}.cpp ${_dpc31emu_rtl_file} VERBATIM)
  set_source_files_properties(${entry} PROPERTIES OBJECT_DEPENDS ${vdir}/ports.checked)
  target_include_directories(${arg_TARGET} PRIVATE ${DPC31EMU_RTL_ADAPTER_DIR})
  target_compile_definitions(${arg_TARGET} PRIVATE DPC31_RTL_CLASS=${prefix}
    DPC31_RTL_HEADER="${prefix}.h" DPC31_RTL_TOP="${arg_TOP}" DPC31_RTL_PROFILE="${arg_PROFILE}")
  target_compile_features(${arg_TARGET} PRIVATE cxx_std_20)
  # Verilator's generated code is not the user's: no warnings, no debug information (as
  # rtl/CMakeLists.txt). Only the entry point is visible: the harness may hold several models,
  # each with its own copy of Verilator's runtime.
  target_compile_options(${arg_TARGET} PRIVATE -w -g0)
  set_target_properties(${arg_TARGET} PROPERTIES PREFIX "" CXX_VISIBILITY_PRESET hidden
    VISIBILITY_INLINES_HIDDEN ON)
endfunction()
