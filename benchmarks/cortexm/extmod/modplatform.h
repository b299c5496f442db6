// py/modsys.c includes extmod's platform names, which the source distribution lacks; this
// port names its machine in mpconfigport.h (MICROPY_HW_BOARD_NAME), so nothing is needed here.
