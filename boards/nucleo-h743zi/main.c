/* SPDX-License-Identifier: MIT */
/* boards/nucleo-h743zi/main.c: the NUCLEO-H743ZI image. Runs the built-in
 * fits at reset and leaves the report in RAM for a debugger to read
 * (`x/s bd_report`, `p bd_result`): with no debugger attached at run time
 * there is nowhere else to send it until the UART transport lands. */
#include "bd_cortexm.h"
#include "bd_selftest.h"
#include "bd_text.h"
#include "nf_budget.h"

_Static_assert(NF_ARENA_BYTES <= BOARD_AXISRAM_BYTES, "arena larger than AXI SRAM");
_Static_assert(NF_BYTES_PCG(NF_MAX_CP + 1, NF_DESIGN_DEGREE, NF_DESIGN_DEGREE) > NF_ARENA_BYTES,
               "NF_MAX_CP leaves arena unused: raise it to the formula's bound");
_Static_assert(BOARD_JOURNAL_ORIGIN + BOARD_JOURNAL_BYTES == BOARD_FLASH_ORIGIN + BOARD_FLASH_BYTES,
               "the journal is the last flash sector");
_Static_assert(BOARD_JOURNAL_BYTES % (128 * 1024) == 0, "H743 flash erases 128 KiB sectors");

/* AXI SRAM: the only region that holds the arena; nothing else goes there. */
static unsigned char arena[NF_ARENA_BYTES]
    __attribute__((section(".arena"), aligned(NF_ARENA_ALIGN)));

/* External, so the linker keeps them and a debugger finds them by name. */
char bd_report[1536];
volatile int bd_result; /* 0 running, 1 every property held, -1 not */

static bd_text_t report;

static void emit(const char *line)
{
    bd_text_str(&report, line);
    bd_text_str(&report, "\n");
}

void bd_fault(unsigned exception)
{
    bd_text_str(&report, "fault exception=");
    bd_text_long(&report, (long)exception);
    bd_text_str(&report, "\n");
    bd_result = -1;
    bd_halt();
}

int main(void)
{
    bd_text_init(&report, bd_report, sizeof bd_report);
    int ok = bd_selftest_run(arena, sizeof arena, emit);
    const unsigned long used = bd_stack_used(), size = bd_stack_size();
    ok &= used < size;
    bd_text_str(&report, "stack used=");
    bd_text_long(&report, (long)used);
    bd_text_str(&report, " size=");
    bd_text_long(&report, (long)size);
    bd_text_str(&report, ok ? "\nresult=pass\n" : "\nresult=fail\n");
    bd_result = ok ? 1 : -1;
    bd_halt();
}
