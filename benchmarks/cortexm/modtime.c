// time and icount: the clock of this board is the instruction count (startup.c). Virtual
// time under QEMU's -icount shift=0 is one nanosecond an instruction, so ticks_us() is
// instructions / 1000, and icount.instructions() the count itself, as ticks (2**30 period,
// time.ticks_diff works on it). icount also holds the benchmark's meter: timed() (a call whose
// instructions are left out), profiled() and profile() (where they go), cold() (an empty
// lookup cache) and spin() (a known count, to check the clock).
#include <string.h>

#include "py/gc.h"
#include "py/runtime.h"
#include "py/mphal.h"
#include "py/smallint.h"

uint64_t clock_count(void);

#define TICKS_PERIOD (MICROPY_PY_TIME_TICKS_PERIOD)
#define TICKS_MAX (TICKS_PERIOD - 1)
#define TICKS_HALFPERIOD (TICKS_PERIOD / 2)

mp_uint_t mp_hal_ticks_us(void) {
    return (mp_uint_t)(clock_count() / 1000u);
}

mp_uint_t mp_hal_ticks_ms(void) {
    return (mp_uint_t)(clock_count() / 1000000u);
}

mp_uint_t mp_hal_ticks_cpu(void) {
    return (mp_uint_t)clock_count();
}

void mp_hal_delay_us(mp_uint_t us) {
    uint64_t end = clock_count() + (uint64_t)us * 1000u;
    while (clock_count() < end) {
    }
}

void mp_hal_delay_ms(mp_uint_t ms) {
    mp_hal_delay_us(ms * 1000u);
}

static mp_obj_t ticks(mp_uint_t v) {
    return MP_OBJ_NEW_SMALL_INT(v & TICKS_MAX);
}

static mp_obj_t time_ticks_ms(void) {
    return ticks(mp_hal_ticks_ms());
}
static MP_DEFINE_CONST_FUN_OBJ_0(time_ticks_ms_obj, time_ticks_ms);

static mp_obj_t time_ticks_us(void) {
    return ticks(mp_hal_ticks_us());
}
static MP_DEFINE_CONST_FUN_OBJ_0(time_ticks_us_obj, time_ticks_us);

static mp_obj_t time_ticks_cpu(void) {
    return ticks(mp_hal_ticks_cpu());
}
static MP_DEFINE_CONST_FUN_OBJ_0(time_ticks_cpu_obj, time_ticks_cpu);

static mp_obj_t time_ticks_diff(mp_obj_t end_in, mp_obj_t start_in) {
    mp_uint_t start = MP_OBJ_SMALL_INT_VALUE(start_in);
    mp_uint_t end = MP_OBJ_SMALL_INT_VALUE(end_in);
    mp_int_t diff = ((end - start + TICKS_HALFPERIOD) & TICKS_MAX) - TICKS_HALFPERIOD;
    return MP_OBJ_NEW_SMALL_INT(diff);
}
static MP_DEFINE_CONST_FUN_OBJ_2(time_ticks_diff_obj, time_ticks_diff);

static mp_obj_t time_ticks_add(mp_obj_t ticks_in, mp_obj_t delta_in) {
    mp_uint_t t = MP_OBJ_SMALL_INT_VALUE(ticks_in);
    mp_int_t delta = mp_obj_get_int(delta_in);
    return ticks(t + delta);
}
static MP_DEFINE_CONST_FUN_OBJ_2(time_ticks_add_obj, time_ticks_add);

static mp_obj_t time_sleep_us(mp_obj_t arg) {
    mp_int_t us = mp_obj_get_int(arg);
    if (us > 0) {
        mp_hal_delay_us(us);
    }
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(time_sleep_us_obj, time_sleep_us);

static mp_obj_t time_sleep_ms(mp_obj_t arg) {
    mp_int_t ms = mp_obj_get_int(arg);
    if (ms > 0) {
        mp_hal_delay_ms(ms);
    }
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(time_sleep_ms_obj, time_sleep_ms);

static mp_obj_t time_sleep(mp_obj_t arg) {
    mp_hal_delay_us((mp_uint_t)(mp_obj_get_float(arg) * 1000000));
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(time_sleep_obj, time_sleep);

static mp_obj_t time_time(void) {
    return mp_obj_new_int_from_ull(clock_count() / 1000000000u);
}
static MP_DEFINE_CONST_FUN_OBJ_0(time_time_obj, time_time);

static mp_obj_t time_time_ns(void) {
    return mp_obj_new_int_from_ull(clock_count());
}
static MP_DEFINE_CONST_FUN_OBJ_0(time_time_ns_obj, time_time_ns);

static const mp_rom_map_elem_t time_globals_table[] = {
    { MP_ROM_QSTR(MP_QSTR___name__), MP_ROM_QSTR(MP_QSTR_time) },
    { MP_ROM_QSTR(MP_QSTR_ticks_ms), MP_ROM_PTR(&time_ticks_ms_obj) },
    { MP_ROM_QSTR(MP_QSTR_ticks_us), MP_ROM_PTR(&time_ticks_us_obj) },
    { MP_ROM_QSTR(MP_QSTR_ticks_cpu), MP_ROM_PTR(&time_ticks_cpu_obj) },
    { MP_ROM_QSTR(MP_QSTR_ticks_diff), MP_ROM_PTR(&time_ticks_diff_obj) },
    { MP_ROM_QSTR(MP_QSTR_ticks_add), MP_ROM_PTR(&time_ticks_add_obj) },
    { MP_ROM_QSTR(MP_QSTR_sleep_us), MP_ROM_PTR(&time_sleep_us_obj) },
    { MP_ROM_QSTR(MP_QSTR_sleep_ms), MP_ROM_PTR(&time_sleep_ms_obj) },
    { MP_ROM_QSTR(MP_QSTR_sleep), MP_ROM_PTR(&time_sleep_obj) },
    { MP_ROM_QSTR(MP_QSTR_time), MP_ROM_PTR(&time_time_obj) },
    { MP_ROM_QSTR(MP_QSTR_time_ns), MP_ROM_PTR(&time_time_ns_obj) },
};
static MP_DEFINE_CONST_DICT(time_globals, time_globals_table);

const mp_obj_module_t mp_module_time = {
    .base = { &mp_type_module },
    .globals = (mp_obj_dict_t *)&time_globals,
};
MP_REGISTER_MODULE(MP_QSTR_time, mp_module_time);

// icount.spin(n): 2 n instructions exactly (a SUBS and a BNE n times), to check the clock
static mp_obj_t icount_spin(mp_obj_t n_in) {
    mp_uint_t n = mp_obj_get_int(n_in);
    if (n) {
        #if defined(__ARM_ARCH_6M__)
        // GCC hands Thumb-1 inline assembly to the assembler in divided syntax
        __asm__ volatile ("1: sub %0, #1\n bne 1b" : "+l" (n) : : "cc");
        #else
        __asm__ volatile ("1: subs %0, %0, #1\n bne 1b" : "+l" (n) : : "cc");
        #endif
    }
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(icount_spin_obj, icount_spin);

// icount.timed(fn): fn, called through C that counts the instructions inside it (the
// outermost such call only) into icount.inside(), and the calls into icount.calls(); bound
// as a method when it is a class's attribute, as a function would be. What it costs beyond
// calling fn directly is the same every call, and is measured by wrapping a C function.
typedef struct {
    mp_obj_base_t base;
    mp_obj_t fn;
} timed_obj_t;

static uint64_t inside_sum;
static uint64_t inside_total;  // as inside_sum, never zeroed (profiled() takes it off)
static mp_uint_t inside_calls;
static int inside_depth;

static mp_obj_t timed_call(mp_obj_t self_in, size_t n_args, size_t n_kw, const mp_obj_t *args) {
    timed_obj_t *self = MP_OBJ_TO_PTR(self_in);
    if (inside_depth) {
        return mp_call_function_n_kw(self->fn, n_args, n_kw, args);
    }
    inside_depth = 1;
    inside_calls++;
    // a heap locked by micropython.heap_lock() is unlocked while the call runs (the part
    // models allocate), so that an allocation of the firmware's own, between them, is found
    mp_uint_t locked = 0;
    while (gc_is_locked()) {
        gc_unlock();
        locked++;
    }
    uint64_t t = clock_count();
    nlr_buf_t nlr;
    if (nlr_push(&nlr) == 0) {
        mp_obj_t ret = mp_call_function_n_kw(self->fn, n_args, n_kw, args);
        nlr_pop();
        while (locked--) {
            gc_lock();
        }
        t = clock_count() - t;
        inside_sum += t;
        inside_total += t;
        inside_depth = 0;
        return ret;
    }
    t = clock_count() - t;
    inside_sum += t;
    inside_total += t;
    inside_depth = 0;
    while (locked--) {
        gc_lock();
    }
    nlr_jump(nlr.ret_val);
}

static MP_DEFINE_CONST_OBJ_TYPE(
    timed_type, MP_QSTR_timed, MP_TYPE_FLAG_BINDS_SELF, call, timed_call);

static mp_obj_t icount_timed(mp_obj_t fn) {
    timed_obj_t *o = mp_obj_malloc(timed_obj_t, &timed_type);
    o->fn = fn;
    return MP_OBJ_FROM_PTR(o);
}
static MP_DEFINE_CONST_FUN_OBJ_1(icount_timed_obj, icount_timed);

// icount.profiled(fn, slot): fn, its instructions (less those inside timed calls during it)
// summed into slot (0-15) of icount.profile(), inclusive of anything it calls: to see where
// a tick's instructions go
#define PROFILE_SLOTS 16
static uint64_t profile_sum[PROFILE_SLOTS];
static mp_uint_t profile_calls[PROFILE_SLOTS];

typedef struct {
    mp_obj_base_t base;
    mp_obj_t fn;
    mp_uint_t slot;
} profiled_obj_t;

static mp_obj_t profiled_call(mp_obj_t self_in, size_t n_args, size_t n_kw, const mp_obj_t *args) {
    profiled_obj_t *self = MP_OBJ_TO_PTR(self_in);
    uint64_t t = clock_count();
    uint64_t in = inside_total;
    mp_obj_t ret = mp_call_function_n_kw(self->fn, n_args, n_kw, args);
    profile_sum[self->slot] += clock_count() - t - (inside_total - in);
    profile_calls[self->slot]++;
    return ret;
}

static MP_DEFINE_CONST_OBJ_TYPE(
    profiled_type, MP_QSTR_profiled, MP_TYPE_FLAG_BINDS_SELF, call, profiled_call);

static mp_obj_t icount_profiled(mp_obj_t fn, mp_obj_t slot_in) {
    mp_uint_t slot = mp_obj_get_int(slot_in);
    if (slot >= PROFILE_SLOTS) {
        mp_raise_ValueError(MP_ERROR_TEXT("slot"));
    }
    profiled_obj_t *o = mp_obj_malloc(profiled_obj_t, &profiled_type);
    o->fn = fn;
    o->slot = slot;
    return MP_OBJ_FROM_PTR(o);
}
static MP_DEFINE_CONST_FUN_OBJ_2(icount_profiled_obj, icount_profiled);

// icount.profile(): [(instructions, calls)] per slot since the last call of it (then zeroed)
static mp_obj_t icount_profile(void) {
    mp_obj_t out = mp_obj_new_list(0, NULL);
    for (int i = 0; i < PROFILE_SLOTS; i++) {
        mp_obj_t pair[2] = {mp_obj_new_int_from_ull(profile_sum[i]), mp_obj_new_int_from_uint(profile_calls[i])};
        mp_obj_list_append(out, mp_obj_new_tuple(2, pair));
        profile_sum[i] = 0;
        profile_calls[i] = 0;
    }
    return out;
}
static MP_DEFINE_CONST_FUN_OBJ_0(icount_profile_obj, icount_profile);

// icount.cold(): MicroPython's attribute lookup cache (one for all maps, by name) emptied, so
// that what runs next finds no position left by code that ran before it: a figure that does
// not depend on what that code was (the part models, between the benchmark's ticks)
static mp_obj_t icount_cold(void) {
    #if MICROPY_OPT_MAP_LOOKUP_CACHE
    memset(MP_STATE_VM(map_lookup_cache), 0, sizeof(MP_STATE_VM(map_lookup_cache)));
    #endif
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_0(icount_cold_obj, icount_cold);

// icount.inside(): instructions inside timed calls since the last call of it (then zeroed)
static mp_obj_t icount_inside(void) {
    uint64_t v = inside_sum;
    inside_sum = 0;
    return mp_obj_new_int_from_ull(v);
}
static MP_DEFINE_CONST_FUN_OBJ_0(icount_inside_obj, icount_inside);

static mp_obj_t icount_calls(void) {
    return mp_obj_new_int_from_uint(inside_calls);
}
static MP_DEFINE_CONST_FUN_OBJ_0(icount_calls_obj, icount_calls);

// icount.instructions(): the instruction count as ticks
static const mp_rom_map_elem_t icount_globals_table[] = {
    { MP_ROM_QSTR(MP_QSTR___name__), MP_ROM_QSTR(MP_QSTR_icount) },
    { MP_ROM_QSTR(MP_QSTR_instructions), MP_ROM_PTR(&time_ticks_cpu_obj) },
    { MP_ROM_QSTR(MP_QSTR_spin), MP_ROM_PTR(&icount_spin_obj) },
    { MP_ROM_QSTR(MP_QSTR_timed), MP_ROM_PTR(&icount_timed_obj) },
    { MP_ROM_QSTR(MP_QSTR_inside), MP_ROM_PTR(&icount_inside_obj) },
    { MP_ROM_QSTR(MP_QSTR_calls), MP_ROM_PTR(&icount_calls_obj) },
    { MP_ROM_QSTR(MP_QSTR_profiled), MP_ROM_PTR(&icount_profiled_obj) },
    { MP_ROM_QSTR(MP_QSTR_profile), MP_ROM_PTR(&icount_profile_obj) },
    { MP_ROM_QSTR(MP_QSTR_cold), MP_ROM_PTR(&icount_cold_obj) },
};
static MP_DEFINE_CONST_DICT(icount_globals, icount_globals_table);

const mp_obj_module_t mp_module_icount = {
    .base = { &mp_type_module },
    .globals = (mp_obj_dict_t *)&icount_globals,
};
MP_REGISTER_MODULE(MP_QSTR_icount, mp_module_icount);
