# Compiler flags, one place. Firmware gets the strict set; host code a lighter one.

# Strict flags for firmware/: portable C99, integer only (odo_fw.h poisons float/double/heap).
set(ODO_FIRMWARE_WARNINGS
  -Wall -Wextra -Wpedantic -Wconversion -Wsign-conversion -Wshadow -Wdouble-promotion
  -Wundef -Wcast-align -Wswitch-enum -Wstrict-prototypes -Wmissing-prototypes
  -Wvla -Wformat=2 -Werror)

function(odo_firmware_flags target)
  target_compile_options(${target} PRIVATE ${ODO_FIRMWARE_WARNINGS}
    "SHELL:-include ${CMAKE_SOURCE_DIR}/firmware/src/odo_fw.h")
endfunction()

# The strict set (libcanard's) for host C too (hal/, hostlib/, host_sim/, tools/,
# tests/): every host target gets it through odo_host_flags or its perf twin.
set(ODO_STRICT_WARNINGS
  -Wconversion -Wsign-conversion -Wdouble-promotion -Wswitch-enum -Wundef -Wcast-align)

function(odo_strict_flags target)
  target_compile_options(${target} PRIVATE ${ODO_STRICT_WARNINGS})
endfunction()

# Host C (tools, HAL backends, tests): warnings as errors, C99 with POSIX.1-2008/XSI (M_PI,
# rename, fsync, clock_gettime).
function(odo_host_flags target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wshadow -Werror ${ODO_STRICT_WARNINGS})
  target_compile_definitions(${target} PRIVATE _XOPEN_SOURCE=700)
  odo_sanitize(${target})
endfunction()

# ASan+UBSan for the host preset. Benchmarks and the Python-loaded library opt out by not calling it.
function(odo_sanitize target)
  if(ODO_SANITIZE)
    target_compile_options(${target} PRIVATE
      -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()

# Code that is measured (odo-bench kernels, the simulator library loaded from Python) is always
# built optimised and without sanitizers, whatever the preset, so figures mean the same everywhere.
function(odo_perf_flags target)
  target_compile_options(${target} PRIVATE -O2)
  target_compile_definitions(${target} PRIVATE NDEBUG)
endfunction()
