/* SPDX-License-Identifier: MIT */
/* boards/mps2-an500/main.c: the QEMU test image. Runs the built-in fits,
 * prints the report through semihosting and ends the emulator with the
 * verdict as its exit status (mk/qemu-test.sh checks both). */
#include "bd_cortexm.h"
#include "bd_selftest.h"
#include "bd_semihost.h"
#include "bd_text.h"
#include "nf_budget.h"

/* Everything shares SSRAM2/3; the linker checks .data + .bss fit beside. */
_Static_assert(NF_ARENA_BYTES + BOARD_STACK_BYTES <= BOARD_RAM_BYTES,
               "arena and stack exceed SSRAM2/3");
_Static_assert(NF_BYTES_PCG(NF_MAX_CP + 1, NF_DESIGN_DEGREE, NF_DESIGN_DEGREE) > NF_ARENA_BYTES,
               "NF_MAX_CP leaves arena unused: raise it to the formula's bound");

static unsigned char arena[NF_ARENA_BYTES]
    __attribute__((section(".arena"), aligned(NF_ARENA_ALIGN)));

static void emit(const char *line)
{
    char buf[320];
    bd_text_t t;
    bd_text_init(&t, buf, sizeof buf);
    bd_text_str(&t, line);
    bd_text_str(&t, "\n");
    bd_semihost_write0(buf);
}

/* A fault must end the emulator with a failure, not leave it to time out. */
void bd_fault(unsigned exception)
{
    char buf[64];
    bd_text_t t;
    bd_text_init(&t, buf, sizeof buf);
    bd_text_str(&t, "fault exception=");
    bd_text_long(&t, (long)exception);
    emit(buf);
    emit("result=fail");
    bd_semihost_exit(0);
}

int main(void)
{
    char buf[96];
    bd_text_t t;
    int ok = bd_selftest_run(arena, sizeof arena, emit);
    const unsigned long used = bd_stack_used(), size = bd_stack_size();
    ok &= used < size; /* the painted bottom word still intact */
    bd_text_init(&t, buf, sizeof buf);
    bd_text_str(&t, "stack used=");
    bd_text_long(&t, (long)used);
    bd_text_str(&t, " size=");
    bd_text_long(&t, (long)size);
    emit(buf);
    emit(ok ? "result=pass" : "result=fail");
    bd_semihost_exit(ok);
}
