/* SPDX-License-Identifier: MIT */
/* bd_cortexm.c: Cortex-M startup without CMSIS: vector table, reset handler
 * (FPU on, .data copied, .bss zeroed, stack painted) and a default handler.
 * The linker script (boards/<b>/link.ld.in) provides the symbols below. */
#include "bd_cortexm.h"
#include "board_config.h"
#include <stdint.h>

extern uint32_t _sidata[], _sdata[], _edata[], _sbss[], _ebss[];
extern uint32_t _sstack[], _estack[];

#define SCB_VTOR (*(volatile uint32_t *)0xE000ED08u)
#define SCB_CPACR (*(volatile uint32_t *)0xE000ED88u)
#define STACK_PAINT 0x5AC3A55Cu

void bd_reset(void);
void bd_default_handler(void);

typedef void (*bd_handler_t)(void);

/* Word 0 is the initial stack pointer, then the handlers: 15 system
 * exceptions and the board's interrupts. The core reads the first two at
 * reset, so the table must sit at the start of the boot region. */
typedef struct bd_vector_table {
    uint32_t *stack_top;
    bd_handler_t handler[15 + BOARD_IRQ_COUNT];
} bd_vector_table_t;

__attribute__((section(".vectors"), used)) const bd_vector_table_t bd_vectors = {
    .stack_top = _estack,
    .handler = {[0] = bd_reset, [1 ... 14 + BOARD_IRQ_COUNT] = bd_default_handler},
};

void bd_reset(void)
{
    /* The FPU first (CP10 and CP11 full access): the compiler may use VFP
     * registers in any function, memcpy and memset included. */
    SCB_CPACR |= 0xFu << 20;
    __asm__ volatile("dsb\n\tisb" ::: "memory");
    /* The boot address need not be where VTOR points (H7: option bytes). */
    SCB_VTOR = (uint32_t)(uintptr_t)&bd_vectors;
    /* Word counts from the linker symbols' addresses: they bound different
     * objects, so C does not let us compare them as pointers. */
    const uintptr_t data = ((uintptr_t)_edata - (uintptr_t)_sdata) / 4;
    const uintptr_t bss = ((uintptr_t)_ebss - (uintptr_t)_sbss) / 4;
    for (uintptr_t i = 0; i < data; i++)
        _sdata[i] = _sidata[i];
    for (uintptr_t i = 0; i < bss; i++)
        _sbss[i] = 0;
    /* Paint the stack up to 64 bytes below our own frame, for bd_stack_used. */
    uintptr_t sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    const uintptr_t paint = (sp - 64 - (uintptr_t)_sstack) / 4;
    for (uintptr_t i = 0; i < paint; i++)
        _sstack[i] = STACK_PAINT;
    main();
    bd_halt();
}

unsigned long bd_stack_size(void)
{
    return (unsigned long)((uintptr_t)_estack - (uintptr_t)_sstack);
}

unsigned long bd_stack_used(void)
{
    const uintptr_t words = ((uintptr_t)_estack - (uintptr_t)_sstack) / 4;
    uintptr_t i = 0;
    while (i < words && _sstack[i] == STACK_PAINT)
        i++;
    return (unsigned long)((words - i) * 4);
}

_Noreturn void bd_halt(void)
{
    for (;;)
        __asm__ volatile("wfi");
}

__attribute__((weak)) void bd_fault(unsigned exception)
{
    (void)exception;
    bd_halt();
}

void bd_default_handler(void)
{
    uint32_t ipsr;
    __asm__ volatile("mrs %0, ipsr" : "=r"(ipsr));
    bd_fault(ipsr & 0x1FFu);
    bd_halt();
}
