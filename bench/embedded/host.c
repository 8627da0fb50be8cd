/* The harness on the host: stdout and the monotonic clock (ns). */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "platform.h"

void fk_line(const char *text)
{
    fputs(text, stdout);
    fputc('\n', stdout);
}

uint32_t fk_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint32_t)((uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec);
}

uint32_t fk_elapsed(uint32_t before, uint32_t after)
{
    return after - before;
}

void fk_exit(int status)
{
    fflush(stdout);
    exit(status);
}
