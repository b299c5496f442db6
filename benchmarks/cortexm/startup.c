// The reset path of a Cortex-M (ARMv6-M or ARMv7-M): the vector table, .data copied and .bss
// cleared, then main(); and the instruction clock, SysTick counting the core clock. Under
// QEMU's -icount shift=0 the core clock is one instruction a nanosecond, so at the MPS2's 25
// MHz SysTick steps once per 40 instructions: count() is instructions to within 40.
#include <stdint.h>

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _estack;
int main(void);

#define SYST_CSR (*(volatile uint32_t *)0xE000E010)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018)
#define RELOAD 0x00FFFFFFu
#define INSTRUCTIONS_PER_STEP 40u  // 1 GHz of instructions (icount shift=0) / 25 MHz

static volatile uint32_t wraps;

void SysTick_Handler(void) {
    wraps++;
}

void clock_start(void) {
    SYST_RVR = RELOAD;
    SYST_CVR = 0;
    SYST_CSR = 7;  // the core clock, the interrupt at every wrap, on
}

// instructions since clock_start(), as a 64-bit count; a wrap between the two reads is seen
// as a change of `wraps` (QEMU takes the interrupt at the loop's branch) and read again
uint64_t clock_count(void) {
    uint32_t w, v;
    do {
        w = wraps;
        v = SYST_CVR;
    } while (w != wraps);
    return ((uint64_t)w * (RELOAD + 1u) + (RELOAD - v)) * INSTRUCTIONS_PER_STEP;
}

void Reset_Handler(void) {
    #if defined(__ARM_FP)
    *(volatile uint32_t *)0xE000ED88 |= 0xFu << 20;  // CPACR: the FPU (CP10, CP11) on
    __asm__ volatile ("dsb\n isb");
    #endif
    uint32_t *src = &_sidata;
    for (uint32_t *dst = &_sdata; dst < &_edata;) {
        *dst++ = *src++;
    }
    for (uint32_t *dst = &_sbss; dst < &_ebss;) {
        *dst++ = 0;
    }
    main();
    for (;;) {
    }
}

static void Fault_Handler(void) {
    extern void sh_exit(int);
    extern void sh_out(const char *, unsigned int);
    sh_out("FAULT\n", 6);
    sh_exit(3);
}

__attribute__((section(".isr_vector"), used))
const void *const vectors[16] = {
    &_estack, Reset_Handler, Fault_Handler, Fault_Handler, Fault_Handler, Fault_Handler,
    Fault_Handler, 0, 0, 0, 0, Fault_Handler, 0, 0, Fault_Handler, SysTick_Handler,
};
