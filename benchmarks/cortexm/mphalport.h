// The HAL the core asks a port for: no pins (this board has no machine module), and no
// interrupt character.
#define mp_hal_pin_obj_t void *

static inline void mp_hal_set_interrupt_char(char c) {
    (void)c;
}
