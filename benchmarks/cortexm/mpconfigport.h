// MicroPython configured as the rp2 port configures it for a Pico (its mpconfigport.h:
// the "extra features" ROM level, computed goto, the Thumb native emitter for viper, single
// precision floats, MPZ long integers, one hash byte per qstr), less what lives in extmod
// (not in the PyPI source distribution this builds from): no json, os, select, random,
// re, machine; time and the instruction clock are this port's own (modtime.c).
#include <stdint.h>
#include <alloca.h>

#define MICROPY_CONFIG_ROM_LEVEL (MICROPY_CONFIG_ROM_LEVEL_EXTRA_FEATURES)

#define MICROPY_GC_STACK_ENTRY_TYPE uint16_t
#define MICROPY_ALLOC_PATH_MAX (128)
#define MICROPY_QSTR_BYTES_IN_HASH (1)

#define MICROPY_PERSISTENT_CODE_LOAD (0)
#define MICROPY_EMIT_THUMB (1)
#define MICROPY_EMIT_INLINE_THUMB (0)
#if defined(__ARM_ARCH_6M__)
#define MICROPY_EMIT_THUMB_ARMV7M (0)
#else
#define MICROPY_EMIT_THUMB_ARMV7M (1)
#endif

#define MICROPY_OPT_COMPUTED_GOTO (1)

#define MICROPY_READER_VFS (0)
#define MICROPY_ENABLE_GC (1)
#define MICROPY_STACK_CHECK_MARGIN (256)
#define MICROPY_ENABLE_EMERGENCY_EXCEPTION_BUF (1)
#define MICROPY_LONGINT_IMPL (MICROPY_LONGINT_IMPL_MPZ)
#define MICROPY_FLOAT_IMPL (MICROPY_FLOAT_IMPL_FLOAT)
#define MICROPY_USE_INTERNAL_ERRNO (1)
#define MICROPY_ENABLE_COMPILER (1)
#define MICROPY_HELPER_REPL (0)
#define MICROPY_KBD_EXCEPTION (0)
#define MICROPY_ENABLE_SCHEDULER (0)
#define MICROPY_PY_SYS_PLATFORM "cortexm"
#define MICROPY_PY_SYS_STDFILES (0)
#define MICROPY_PY_SYS_PATH_ARGV_DEFAULTS (1)
#define MICROPY_PY_BUILTINS_INPUT (0)
#define MICROPY_PY_BUILTINS_HELP (0)
#define MICROPY_PY_IO_FILEIO (0)
#define MICROPY_PY_MICROPYTHON_RINGIO (0)
#define MICROPY_PY_ERRNO (1)

// extmod's: not in the source distribution
#define MICROPY_PY_TIME (0)
#define MICROPY_PY_SELECT (0)
#define MICROPY_PY_ASYNCIO (0)
#define MICROPY_PY_UCTYPES (0)
#define MICROPY_PY_DEFLATE (0)
#define MICROPY_PY_JSON (0)
#define MICROPY_PY_OS (0)
#define MICROPY_PY_RE (0)
#define MICROPY_PY_HEAPQ (0)
#define MICROPY_PY_HASHLIB (0)
#define MICROPY_PY_BINASCII (0)
#define MICROPY_PY_RANDOM (0)
#define MICROPY_PY_MACHINE (0)
#define MICROPY_PY_PLATFORM (0)
#define MICROPY_PY_FRAMEBUF (0)
#define MICROPY_PY_VFS (0)
#define MICROPY_PY_CMATH (0)

#define MICROPY_HW_BOARD_NAME "qemu-mps2"
#define MICROPY_HW_MCU_NAME "cortex-m"

#define MP_SSIZE_MAX (0x7fffffff)
typedef intptr_t mp_int_t;
typedef uintptr_t mp_uint_t;
typedef long mp_off_t;

#define MICROPY_MAKE_POINTER_CALLABLE(p) ((void *)((mp_uint_t)(p) | 1))
#define MP_STATE_PORT MP_STATE_VM
