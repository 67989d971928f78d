# CTest Install.exports: the dynamic symbol tables of libdpc31emu.so and
# libdpc31emu_segment_outputs.so hold no fmt symbol (packaging/hide_fmt.ver, docs/install.md), and
# still the API: the C HAL's dpc31_create and dpc31emu_version, the chip's dpc31::Chip members
# and, in the outputs' library, dpc31::SegmentOutputs.
#   cmake -DNM=... -DEMU=.../libdpc31emu.so -DOUTPUTS=.../libdpc31emu_segment_outputs.so -P check_exports.cmake
function(exports lib out)
  execute_process(COMMAND ${NM} -D --defined-only ${ARGN} ${lib} OUTPUT_VARIABLE table
    RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${NM} -D ${lib}: exit ${rc}")
  endif()
  set(${out} "${table}" PARENT_SCOPE)
endfunction()

# A symbol of namespace fmt, by its mangled name (packaging/hide_fmt.ver): a function, data, a
# const member, a local static, typeinfo, its name, a vtable, a guard variable.
function(expect lib table mangled)
  string(REGEX MATCHALL " _Z(T[ISV]|GV)?Z?NK?3fmt[^\n]*" leaked "${mangled}")
  list(LENGTH leaked n)
  if(n GREATER 0)
    list(GET leaked 0 first)
    message(FATAL_ERROR "${lib} exports ${n} fmt symbols, the first: ${first}")
  endif()
  foreach(want IN LISTS ARGN)
    string(FIND "${table}" "${want}" at)
    if(at EQUAL -1)
      message(FATAL_ERROR "${lib} does not export ${want}")
    endif()
  endforeach()
endfunction()

exports(${EMU} emu -C)
exports(${EMU} emu_mangled)
expect(${EMU} "${emu}" "${emu_mangled}" " T dpc31_create" " T dpc31emu_version" " dpc31::Chip::read(")
exports(${OUTPUTS} outputs -C)
exports(${OUTPUTS} outputs_mangled)
expect(${OUTPUTS} "${outputs}" "${outputs_mangled}" "dpc31::SegmentOutputs::")
message(STATUS "no fmt symbol exported; the API is")
