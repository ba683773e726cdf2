# ctest firmware.layers: the build enforces the firmware's layers (issue 17 item 3). A module
# compiled with odo_core's include path cannot include hal/hal.h nor app/odo_loop.h; with
# odo_app's it can (the positive control, so the test fails for the right reason).
#
#   cmake -DCC=<c compiler> -DSOURCE_DIR=<repo> -DWORK_DIR=<scratch dir>
#         -DCORE_INCLUDES=<dirs, |-separated> -DAPP_INCLUDES=<dirs, |-separated> -P check_layers.cmake
foreach(var CC SOURCE_DIR WORK_DIR CORE_INCLUDES APP_INCLUDES)
  if(NOT DEFINED ${var} OR "${${var}}" STREQUAL "")
    message(FATAL_ERROR "check_layers.cmake: -D${var}=... is required")
  endif()
endforeach()

file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
file(WRITE "${WORK_DIR}/uses_hal.c" "#include \"hal.h\"\nint odo_probe(void);\nint odo_probe(void) { return 0; }\n")
file(WRITE "${WORK_DIR}/uses_loop.c" "#include \"odo_loop.h\"\nint odo_probe(void);\nint odo_probe(void) { return 0; }\n")

function(compile name includes out_rc out_log)
  string(REPLACE "|" ";" _dirs "${includes}")
  set(_flags -std=c99 -include "${SOURCE_DIR}/firmware/src/odo_fw.h")
  foreach(d IN LISTS _dirs)
    list(APPEND _flags "-I${d}")
  endforeach()
  execute_process(
    COMMAND "${CC}" ${_flags} -c "${WORK_DIR}/${name}.c" -o "${WORK_DIR}/${name}.o"
    RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _err)
  set(${out_rc} "${_rc}" PARENT_SCOPE)
  set(${out_log} "${_out}${_err}" PARENT_SCOPE)
endfunction()

set(_failures "")
foreach(probe uses_hal uses_loop)
  compile(${probe} "${APP_INCLUDES}" _rc _log)
  if(_rc EQUAL 0)
    message(STATUS "ok   ${probe}.c compiles with odo_app's include path (positive control)")
  else()
    string(APPEND _failures "- ${probe}.c must compile with odo_app's include path:\n${_log}\n")
  endif()
  compile(${probe} "${CORE_INCLUDES}" _rc _log)
  if(NOT _rc EQUAL 0 AND _log MATCHES "(hal|odo_loop)\\.h")
    message(STATUS "ok   ${probe}.c does not compile with odo_core's include path")
  else()
    string(APPEND _failures "- ${probe}.c must not compile with odo_core's include path "
      "(rc ${_rc}):\n${_log}\n")
  endif()
endforeach()

if(NOT _failures STREQUAL "")
  message(FATAL_ERROR "firmware layers are not enforced:\n${_failures}")
endif()
