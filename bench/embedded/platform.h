/* What the harness needs from where it runs: an emulated Cortex-M under QEMU (startup.c:
 * semihosting output, SysTick) or the host (host.c: stdio, clock_gettime). */
#ifndef FK_PLATFORM_H
#define FK_PLATFORM_H

#include <stdint.h>

/* Write one line (the newline is added). */
void fk_line(const char *text);
/* A free-running counter: SysTick ticks on the MCU (counts down, 24 bits, 25 MHz on mps2 and
 * 16 MHz on microbit: with QEMU -icount shift=0 one instruction is 1 ns of virtual time), the
 * monotonic clock in ns on the host (counts up). fk_elapsed(a, b) is the count from a to b. */
uint32_t fk_now(void);
uint32_t fk_elapsed(uint32_t before, uint32_t after);
/* Leave with an exit status (semihosting SYS_EXIT on the MCU). */
void fk_exit(int status);

#endif
