/// Firmware-wide private prelude. Every firmware/ translation unit gets it first, through the
/// build (-include), never through a public header, so tests and host tools stay free to use
/// double precision for their references.
///
/// It pulls in the only standard headers the core may use, then poisons every identifier that
/// would make the core non-portable: floating point, the heap, stdio and OS calls. Using any of
/// them after this point is a hard compile error ("attempt to use poisoned ..."), which the
/// test tests/firmware/check_poison.cmake proves.
#ifndef ODO_FW_H
#define ODO_FW_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#pragma GCC poison float double
#pragma GCC poison malloc calloc realloc free alloca
#pragma GCC poison printf fprintf sprintf snprintf puts fopen fread fwrite
#pragma GCC poison time clock sleep usleep exit abort system getenv

#endif
