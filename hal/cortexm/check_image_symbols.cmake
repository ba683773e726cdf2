# Post-build check of the Cortex-M4 image (cmake -DNM=<nm> -DELF=<elf> -P this file): fail the
# build if the final link pulled in floating-point, heap or stdio code. Compiling firmware/ with the
# poison prelude stops it in our sources; this catches it arriving through libgcc/newlib (a literal
# that promotes, a helper that calls printf). tests/firmware/check_cm4_image.py repeats the check
# from ctest with the same list.
if(NOT NM OR NOT ELF)
  message(FATAL_ERROR "usage: cmake -DNM=<arm-none-eabi-nm> -DELF=<image.elf> -P ${CMAKE_CURRENT_LIST_FILE}")
endif()

execute_process(COMMAND "${NM}" --defined-only "${ELF}"
  OUTPUT_VARIABLE _out ERROR_VARIABLE _err RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "${NM} failed on ${ELF}: ${_err}")
endif()

set(_forbidden
  "^__aeabi_[df]"                                  # AEABI soft-float (double, float)
  "^__(add|sub|mul|div|neg)[sdt]f3$"               # libgcc soft-float arithmetic
  "^__(eq|ne|lt|le|gt|ge|unord|cmp)[sdt]f2$"       # libgcc soft-float compares
  "^__(float|fix)"                                 # int <-> float conversions
  "^__(extend|trunc)[sdt]f"                        # float <-> double
  "^(_printf_float|_scanf_float|_dtoa_r|__ieee754)"  # newlib floating-point formatting/maths
  "^_*(malloc|calloc|realloc|free|sbrk|malloc_r|calloc_r|realloc_r|free_r|sbrk_r)$"  # heap
  "^__malloc_"
  "printf"                                         # stdio formatting
  "^_*puts(_r)?$")

string(REPLACE "\n" ";" _lines "${_out}")
set(_bad "")
foreach(line IN LISTS _lines)
  string(REGEX REPLACE "^[0-9a-fA-F]* *[A-Za-z] " "" _sym "${line}")
  if(_sym STREQUAL "")
    continue()
  endif()
  foreach(re IN LISTS _forbidden)
    if(_sym MATCHES "${re}")
      list(APPEND _bad "${_sym}")
      break()
    endif()
  endforeach()
endforeach()

if(_bad)
  list(REMOVE_DUPLICATES _bad)
  list(JOIN _bad "\n  " _bad_text)
  message(FATAL_ERROR
    "${ELF} links floating-point, heap or stdio code, which the image must not contain:\n"
    "  ${_bad_text}\n"
    "Find who pulls them in with the link map (odo_image.map, 'Archive member included').")
endif()
message(STATUS "odo_image: no soft-float, heap or stdio symbols")
