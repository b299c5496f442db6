// A bare MicroPython for a Cortex-M under QEMU: runs one script from the host's files, read
// through semihosting, with the arguments QEMU passes (-semihosting-config arg=...):
//     cortexm [-p DIR:DIR...] SCRIPT [ARG...]
// -p puts the directories on sys.path ahead of the script's (as MICROPYPATH does on the unix
// port). Output goes to QEMU's stdout; the exit code is 0, or 1 after an uncaught exception.
#include <stdlib.h>
#include <string.h>

#include "py/builtin.h"
#include "py/compile.h"
#include "py/gc.h"
#include "py/lexer.h"
#include "py/mperrno.h"
#include "py/mphal.h"
#include "py/runtime.h"
#include "py/stackctrl.h"
#include "shared/runtime/gchelper.h"
#include "semihost.h"

#ifndef HEAP_KB
#define HEAP_KB 1024
#endif

void clock_start(void);

static char heap[HEAP_KB * 1024];
static char cmdline[1024];

mp_uint_t mp_hal_stdout_tx_strn(const char *str, size_t len) {
    sh_out(str, len);
    return len;
}

// a file of the host's, whole, in a heap buffer; NULL if it cannot be opened
static char *read_file(const char *path, size_t *len) {
    int fd = sh_open(path, 1);  // "rb"
    if (fd < 0) {
        return NULL;
    }
    int n = sh_flen(fd);
    if (n < 0) {
        sh_close(fd);
        return NULL;
    }
    char *buf = m_new(char, n + 1);
    if (sh_read(fd, buf, n) != 0) {
        sh_close(fd);
        m_del(char, buf, n + 1);
        return NULL;
    }
    sh_close(fd);
    buf[n] = 0;
    *len = n;
    return buf;
}

mp_lexer_t *mp_lexer_new_from_file(qstr filename) {
    size_t len;
    char *src = read_file(qstr_str(filename), &len);
    if (src == NULL) {
        mp_raise_OSError(MP_ENOENT);
    }
    // the lexer keeps the buffer (free_len non-zero: it frees it when done)
    return mp_lexer_new_from_str_len(filename, src, len, len + 1);
}

static int exists(const char *path) {
    int fd = sh_open(path, 1);
    if (fd < 0) {
        return 0;
    }
    sh_close(fd);
    return 1;
}

// a path ending in .py or .mpy is a file if it opens; any other that opens is a directory
// (a package): the host's open() takes a directory too, and no module here lacks a suffix
mp_import_stat_t mp_import_stat(const char *path) {
    if (!exists(path)) {
        return MP_IMPORT_STAT_NO_EXIST;
    }
    size_t n = strlen(path);
    if ((n > 3 && strcmp(path + n - 3, ".py") == 0) || (n > 4 && strcmp(path + n - 4, ".mpy") == 0)) {
        return MP_IMPORT_STAT_FILE;
    }
    return MP_IMPORT_STAT_DIR;
}

mp_obj_t mp_builtin_open(size_t n_args, const mp_obj_t *args, mp_map_t *kwargs) {
    mp_raise_OSError(MP_ENOENT);
}
MP_DEFINE_CONST_FUN_OBJ_KW(mp_builtin_open_obj, 1, mp_builtin_open);

void gc_collect(void) {
    gc_collect_start();
    gc_helper_collect_regs_and_stack();
    gc_collect_end();
}

void nlr_jump_fail(void *val) {
    sh_out("nlr_jump_fail\n", 14);
    sh_exit(3);
}

void MP_NORETURN __fatal_error(const char *msg) {
    sh_out(msg, strlen(msg));
    sh_exit(3);
}

#ifndef NDEBUG
void MP_WEAK __assert_func(const char *file, int line, const char *func, const char *expr) {
    sh_out("assert: ", 8);
    sh_out(expr, strlen(expr));
    sh_out("\n", 1);
    sh_exit(3);
}
#endif

static void add_paths(char *dirs) {
    // prepended in order, ahead of the script's own directory
    size_t at = 0;
    for (char *d = strtok(dirs, ":"); d; d = strtok(NULL, ":")) {
        mp_obj_list_t *path = MP_OBJ_TO_PTR(mp_sys_path);
        mp_obj_list_append(mp_sys_path, mp_obj_new_str(d, strlen(d)));
        // move the new last entry to position `at`
        mp_obj_t last = path->items[path->len - 1];
        memmove(&path->items[at + 1], &path->items[at], (path->len - 1 - at) * sizeof(mp_obj_t));
        path->items[at++] = last;
    }
}

static int run(const char *script) {
    nlr_buf_t nlr;
    if (nlr_push(&nlr) == 0) {
        mp_lexer_t *lex = mp_lexer_new_from_file(qstr_from_str(script));
        qstr source = lex->source_name;
        mp_store_global(MP_QSTR___file__, MP_OBJ_NEW_QSTR(source));
        mp_parse_tree_t tree = mp_parse(lex, MP_PARSE_FILE_INPUT);
        mp_obj_t fn = mp_compile(&tree, source, false);
        mp_call_function_0(fn);
        nlr_pop();
        return 0;
    }
    mp_obj_t exc = MP_OBJ_FROM_PTR(nlr.ret_val);
    if (mp_obj_is_subclass_fast(MP_OBJ_FROM_PTR(mp_obj_get_type(exc)), MP_OBJ_FROM_PTR(&mp_type_SystemExit))) {
        mp_obj_t code = mp_obj_exception_get_value(exc);
        if (code == mp_const_none) {
            return 0;
        }
        if (mp_obj_is_int(code)) {
            return mp_obj_get_int(code);
        }
        mp_obj_print(code, PRINT_STR);
        mp_hal_stdout_tx_strn("\n", 1);
        return 1;
    }
    mp_obj_print_exception(&mp_plat_print, exc);
    return 1;
}

int main(void) {
    clock_start();
    mp_stack_ctrl_init();
    mp_stack_set_limit(32 * 1024);
    gc_init(heap, heap + sizeof(heap));
    mp_init();
    int code = 2;
    if (sh_cmdline(cmdline, sizeof(cmdline) - 1) == 0) {
        char *argv[32];
        int argc = 0;
        for (char *a = strtok(cmdline, " "); a && argc < 32; a = strtok(NULL, " ")) {
            argv[argc++] = a;
        }
        int i = 1;  // argv[0]: the program's name
        char *dirs = NULL;
        if (i + 1 < argc && strcmp(argv[i], "-p") == 0) {
            dirs = argv[i + 1];
            i += 2;
        }
        if (i < argc) {
            for (int k = i; k < argc; k++) {
                mp_obj_list_append(mp_sys_argv, mp_obj_new_str(argv[k], strlen(argv[k])));
            }
            // the script's directory first on sys.path, as the unix port does
            const char *slash = strrchr(argv[i], '/');
            mp_obj_list_t *path = MP_OBJ_TO_PTR(mp_sys_path);
            path->items[0] = slash ? mp_obj_new_str(argv[i], slash - argv[i]) : MP_OBJ_NEW_QSTR(MP_QSTR_);
            if (dirs) {
                // strtok is done with cmdline's words: dirs is its own word
                add_paths(dirs);
            }
            code = run(argv[i]);
        } else {
            sh_out("usage: cortexm [-p DIR:DIR...] SCRIPT [ARG...]\n", 48);
        }
    }
    mp_deinit();
    sh_exit(code);
}
