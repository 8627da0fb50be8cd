"""A C program that runs generated table or exact code from the command line (not a test module).

:data:`HARNESS` reads points from stdin, prints ``NAME_eval``'s outputs (one line per point),
then runs a few hundred fuzzy-PI steps over extreme samples (``-DWITH_FPI``, with NaN samples
under ``-DWITH_NAN``), so that a sanitized build exercises every entry point. Format it with
``name``, ``t`` (the C number type), ``ni``/``no`` (inputs, outputs), ``fmt`` (scanf's) and
``big`` (an extreme sample).
"""

HARNESS = r"""
#include <stdio.h>
#include <math.h>
#include "{name}.h"

/* A few hundred fuzzy-PI steps over extreme samples, so the sanitizers see the step too. */
static int run_fpi(void)
{{
#ifdef WITH_FPI
    {name}_fpi_t c;
    long k;
    {t} meas;
    {name}_fpi_init(&c, 1e3f, 1e3f, 10.0f, -0.5f, 0.5f);
    for (k = 0; k < 400; k++) {{
        meas = ({t})(k % 7 == 0 ? {big} : (k % 5 == 0 ? -{big} : (k % 3)));
#ifdef WITH_NAN
        if (k % 11 == 0) {{
            meas = NAN;
        }}
#endif
        printf("u %.17g\n", (double){name}_fpi_step(&c, ({t})1, meas));
    }}
#endif
    return 0;
}}

int main(void)
{{
    {t} in[{ni}], out[{no}];
    double x[{ni}];
    int i;
    for (;;) {{
        for (i = 0; i < {ni}; i++) {{
            if (scanf("{fmt}", &x[i]) != 1) {{
                return run_fpi();
            }}
            in[i] = ({t})x[i];
        }}
        {name}_eval(in, out);
        for (i = 0; i < {no}; i++) {{
            printf("%.17g%c", (double)out[i], i + 1 < {no} ? ' ' : '\n');
        }}
    }}
}}
"""
