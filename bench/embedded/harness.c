/* Test-vector harness for generated code, the same source on the MCU (under QEMU) and on the
 * host: every output is printed (or hashed) as its bit pattern, so the two runs' text must be
 * identical line for line; only the TIME lines differ (they count SysTick ticks on the MCU and
 * nanoseconds on the host).
 *
 * Configured by the driver (run.py) with -D:
 *   FK_EVAL_HEADER "NAME.h", FK_EVAL NAME_eval, FK_EVAL_T float | int16_t, FK_NIN, FK_NOUT,
 *     FK_POINTS (random points), FK_AMPLITUDE (float inputs: uniform in +-amplitude)
 *   FK_CTL_HEADER "NAME_controller.h", FK_CTL NAME_controller (the controller's prefix),
 *     FK_LOG_N (samples in NAME_log_data.c: fk_log_force[n][3], fk_log_rot[n][9])
 */
#include <stdint.h>
#include <string.h>

#include "platform.h"

#define FK_CAT2(a, b) a##b
#define FK_CAT(a, b) FK_CAT2(a, b)

static char fk_text[200];
static unsigned fk_len;

static void fk_put(const char *s)
{
    while (*s != '\0' && fk_len < sizeof(fk_text) - 1) {
        fk_text[fk_len++] = *s++;
    }
    fk_text[fk_len] = '\0';
}

static void fk_hex(uint32_t v, int digits)
{
    static const char hex[] = "0123456789abcdef";
    char buf[10];
    int i;
    buf[0] = ' ';
    for (i = 0; i < digits; i++) {
        buf[digits - i] = hex[(v >> (4 * i)) & 0xFu];
    }
    buf[digits + 1] = '\0';
    fk_put(buf);
}

static void fk_dec(uint32_t v)
{
    char buf[12];
    int i = 11;
    buf[i] = '\0';
    do {
        buf[--i] = (char)('0' + v % 10u);
        v /= 10u;
    } while (v != 0u);
    buf[--i] = ' ';
    fk_put(buf + i);
}

static void fk_start(const char *tag)
{
    fk_len = 0;
    fk_text[0] = '\0';
    fk_put(tag);
}

static void fk_end(void)
{
    fk_line(fk_text);
}

/* FNV-1a, 64 bits, over 32-bit words */
static uint64_t fk_hash = 14695981039346656037ull;

static void fk_mix(uint32_t word)
{
    int i;
    for (i = 0; i < 4; i++) {
        fk_hash ^= (word >> (8 * i)) & 0xFFu;
        fk_hash *= 1099511628211ull;
    }
}

static uint32_t fk_rng = 12345u;

static uint32_t fk_next(void)
{
    fk_rng = fk_rng * 1664525u + 1013904223u; /* Numerical Recipes LCG */
    return fk_rng;
}

static uint32_t fk_float_bits(float x)
{
    uint32_t b;
    memcpy(&b, &x, sizeof(b));
    return b;
}

static void fk_time_line(const char *what, uint32_t calls, uint64_t total, uint64_t calib,
                         uint32_t max)
{
    fk_start("TIME ");
    fk_put(what);
    fk_dec(calls);
    fk_dec((uint32_t)(total >> 32));
    fk_dec((uint32_t)total);
    fk_dec((uint32_t)(calib >> 32));
    fk_dec((uint32_t)calib);
    fk_dec(max);
    fk_end();
}

#ifdef FK_EVAL
#include FK_EVAL_HEADER

typedef FK_EVAL_T fk_t;

/* called through a volatile pointer: the compiler cannot inline it into the timed region */
static void (*volatile fk_eval_fn)(const fk_t *, fk_t *) = FK_EVAL;

static uint32_t fk_bits(fk_t v)
{
#ifdef FK_Q15
    return (uint32_t)(uint16_t)v;
#else
    return fk_float_bits(v);
#endif
}

static void fk_print_point(const char *tag, uint32_t k, const fk_t in[FK_NIN],
                           const fk_t out[FK_NOUT])
{
    int i;
    fk_start(tag);
    fk_dec(k);
    for (i = 0; i < FK_NIN; i++) {
        fk_hex(fk_bits(in[i]), 8);
    }
    fk_put(" ->");
    for (i = 0; i < FK_NOUT; i++) {
        fk_hex(fk_bits(out[i]), 8);
    }
    fk_end();
}

#ifdef FK_Q15
static const fk_t fk_edges[] = {-32768, -32767, -16384, -1, 0, 1, 16384, 32766, 32767};
#else
/* bit patterns: 0, -0, +-1, +-0.5, +-1e30, +-inf, NaN, -NaN, +-FLT_MAX, +-FLT_MIN, denormal */
static const uint32_t fk_edge_bits[] = {
    0x00000000u, 0x80000000u, 0x3f800000u, 0xbf800000u, 0x3f000000u, 0xbf000000u,
    0x7149f2cau, 0xf149f2cau, 0x7f800000u, 0xff800000u, 0x7fc00000u, 0xffc00000u,
    0x7f7fffffu, 0xff7fffffu, 0x00800000u, 0x80800000u, 0x00000001u,
};
#endif

static fk_t fk_edge(unsigned i)
{
#ifdef FK_Q15
    return fk_edges[i];
#else
    float x;
    memcpy(&x, &fk_edge_bits[i], sizeof(x));
    return x;
#endif
}

static unsigned fk_n_edges(void)
{
#ifdef FK_Q15
    return (unsigned)(sizeof(fk_edges) / sizeof(fk_edges[0]));
#else
    return (unsigned)(sizeof(fk_edge_bits) / sizeof(fk_edge_bits[0]));
#endif
}

static fk_t fk_random_input(void)
{
#ifdef FK_Q15
    return (fk_t)(int16_t)(fk_next() >> 16);
#else
    /* uniform in [-amplitude, amplitude): exact int -> float, a power of two, one rounding */
    int32_t r = (int32_t)(fk_next() >> 8) - 8388608;
    return ((float)r * (1.0f / 8388608.0f)) * FK_AMPLITUDE;
#endif
}

static void fk_run_eval(void)
{
    fk_t in[FK_NIN], out[FK_NOUT];
    unsigned n = fk_n_edges(), combos = 1, c;
    uint32_t k, t0, t1, d, max = 0;
    uint64_t total = 0, calib = 0;
    int i;
    for (i = 0; i < FK_NIN; i++) {
        combos *= n;
    }
    /* every combination of edge values on every input */
    for (c = 0; c < combos; c++) {
        unsigned rest = c;
        for (i = 0; i < FK_NIN; i++) {
            in[i] = fk_edge(rest % n);
            rest /= n;
        }
        fk_eval_fn(in, out);
        fk_print_point("EDGE", c, in, out);
    }
    for (k = 0; k < FK_POINTS; k++) {
        for (i = 0; i < FK_NIN; i++) {
            in[i] = fk_random_input();
        }
        t0 = fk_now();
        fk_eval_fn(in, out);
        t1 = fk_now();
        d = fk_elapsed(t0, t1);
        total += d;
        max = d > max ? d : max;
        t0 = fk_now(); /* the two reads alone: subtracted, so the call itself counts */
        t1 = fk_now();
        calib += fk_elapsed(t0, t1);
        for (i = 0; i < FK_NIN; i++) {
            fk_mix(fk_bits(in[i]));
        }
        for (i = 0; i < FK_NOUT; i++) {
            fk_mix(fk_bits(out[i]));
        }
        if (k % 997u == 0u) {
            fk_print_point("POINT", k, in, out);
        }
        if ((k + 1u) % 5000u == 0u) {
            fk_start("HASH");
            fk_dec(k + 1u);
            fk_hex((uint32_t)(fk_hash >> 32), 8);
            fk_hex((uint32_t)fk_hash, 8);
            fk_end();
        }
    }
    fk_start("EVAL");
    fk_dec(FK_POINTS);
    fk_dec(combos);
    fk_hex((uint32_t)(fk_hash >> 32), 8);
    fk_hex((uint32_t)fk_hash, 8);
    fk_end();
    fk_time_line("eval", FK_POINTS, total, calib, max);
}
#endif

#ifdef FK_CTL
#include FK_CTL_HEADER

extern const float fk_log_force[FK_LOG_N][3];
extern const float fk_log_rot[FK_LOG_N][9];

typedef FK_CAT(FK_CTL, _t) fk_ctl_t;

static uint32_t (*volatile fk_step_fn)(fk_ctl_t *, const float *, const float *, float *) =
    FK_CAT(FK_CTL, _step);

static fk_ctl_t fk_ctl;

static void fk_run_controller(void)
{
    float u[3];
    uint32_t k, status, t0, t1, d, max = 0;
    uint64_t total = 0, calib = 0;
    int i;
    FK_CAT(FK_CTL, _init)(&fk_ctl);
    for (k = 0; k < FK_LOG_N; k++) {
        t0 = fk_now();
        status = fk_step_fn(&fk_ctl, fk_log_force[k], fk_log_rot[k], u);
        t1 = fk_now();
        d = fk_elapsed(t0, t1);
        total += d;
        max = d > max ? d : max;
        t0 = fk_now();
        t1 = fk_now();
        calib += fk_elapsed(t0, t1);
        fk_start("TICK");
        fk_dec(k);
        fk_dec(d);
        fk_dec(fk_elapsed(t0, t1));
        fk_end();
        fk_start("STEP");
        fk_dec(k);
        fk_hex(status, 2);
        for (i = 0; i < 3; i++) {
            fk_hex(fk_float_bits(u[i]), 8);
        }
        fk_end();
    }
    fk_time_line("step", FK_LOG_N, total, calib, max);
}
#endif

int main(void)
{
#ifdef FK_EVAL
    fk_run_eval();
#endif
#ifdef FK_CTL
    fk_run_controller();
#endif
    fk_line("DONE");
    return 0;
}
