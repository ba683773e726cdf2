# ctest firmware.poison: proves that firmware/src/odo_fw.h makes floating point and the heap a hard
# compile error under the exact firmware flags, and that the same flags compile clean code (so the
# test fails for the right reason, not because the flags or paths are broken).
#
#   cmake -DCC=<c compiler> -DSOURCE_DIR=<repo> -DWORK_DIR=<scratch dir>
#         "-DWARNINGS=<firmware warnings, ;-list or space separated>" -P check_poison.cmake
foreach(var CC SOURCE_DIR WORK_DIR WARNINGS)
  if(NOT DEFINED ${var} OR "${${var}}" STREQUAL "")
    message(FATAL_ERROR "check_poison.cmake: -D${var}=... is required")
  endif()
endforeach()

separate_arguments(_warnings UNIX_COMMAND "${WARNINGS}")
set(_flags -std=c99 ${_warnings}
  -include "${SOURCE_DIR}/firmware/src/odo_fw.h"
  -I "${SOURCE_DIR}/firmware/include")

file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

# Each snippet is otherwise warning-free under the strict flags (prototypes, conversions, a
# declaration of malloc), so the only way it can fail is the poison. Messages are collected as one
# string, not a list: compiler output is full of semicolons.
file(WRITE "${WORK_DIR}/clean.c" [=[
#include "odo/odo_types.h"
int32_t odo_probe(int32_t a);
int32_t odo_probe(int32_t a) { return a + 1; }
]=])
file(WRITE "${WORK_DIR}/uses_double.c" [=[
#include "odo/odo_types.h"
int32_t odo_probe(int32_t a);
int32_t odo_probe(int32_t a) { double h = 0.5; return a + (int32_t)h; }
]=])
file(WRITE "${WORK_DIR}/uses_float.c" [=[
#include "odo/odo_types.h"
int32_t odo_probe(int32_t a);
int32_t odo_probe(int32_t a) { float h = 0.5f; return a + (int32_t)h; }
]=])
file(WRITE "${WORK_DIR}/uses_malloc.c" [=[
#include "odo/odo_types.h"
void *malloc(size_t n);
void *odo_probe(size_t n);
void *odo_probe(size_t n) { return malloc(n); }
]=])

set(_failures "")

function(compile name out_rc out_log)
  execute_process(
    COMMAND "${CC}" ${_flags} -c "${WORK_DIR}/${name}.c" -o "${WORK_DIR}/${name}.o"
    RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _err)
  set(${out_rc} "${_rc}" PARENT_SCOPE)
  set(${out_log} "${_out}${_err}" PARENT_SCOPE)
endfunction()

compile(clean _rc _log)
if(_rc EQUAL 0)
  message(STATUS "ok   clean.c compiles with the firmware flags (positive control)")
else()
  string(APPEND _failures "- clean.c must compile with the firmware flags but did not "
    "(the flags or include paths are broken, so the poison checks below prove nothing):\n${_log}\n")
endif()

foreach(pair "uses_double:double" "uses_float:float" "uses_malloc:malloc")
  string(REPLACE ":" ";" pair "${pair}")
  list(GET pair 0 name)
  list(GET pair 1 word)
  compile(${name} _rc _log)
  if(_rc EQUAL 0)
    string(APPEND _failures "- ${name}.c compiled, but `${word}` must be poisoned by odo_fw.h\n")
  elseif(NOT _log MATCHES "poisoned" OR NOT _log MATCHES "${word}")
    string(APPEND _failures "- ${name}.c failed, but not because `${word}` is poisoned:\n${_log}\n")
  else()
    message(STATUS "ok   ${name}.c rejected: `${word}` is poisoned")
  endif()
endforeach()

if(NOT _failures STREQUAL "")
  # message(FATAL_ERROR) reflows its text; print the compiler output verbatim first.
  message(NOTICE "firmware.poison FAILED:\n${_failures}")
  message(FATAL_ERROR "firmware.poison FAILED (reasons above)")
endif()
message(STATUS "firmware.poison: float, double and malloc are compile errors in firmware/")
