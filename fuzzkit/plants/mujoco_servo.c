/* The MuJoCo IRB 140's servo reference ramp as MuJoCo's control callback (mjcb_control).
 *
 * MuJoCo calls the callback once per physics step, inside mj_step after the position and
 * velocity stages and before the actuator forces. Before substep s (1..n) of a controller period
 * it sets every actuator's control to
 *
 *     ctrl[i] = prev[i] + (s / n) * (ref[i] - prev[i]) + feed[i]
 *
 * (the previous period's joint reference, the new one, the velocity feed-forward), in the
 * operation order of the Python ramp in fuzzkit/plants/mujoco_arm.py, so the two give the same
 * doubles. From the second substep on it also marks the actuators whose force in the previous
 * substep reached 99.9 % of their limit (the last substep's force is checked by the caller after
 * mj_step, since the callback runs before the forces of its own step are computed).
 *
 * All state is per MjData, in d->userdata (layout below, written by
 * fuzzkit/plants/mujoco_servo.py): no static state, so one callback serves every MjData of every
 * thread. The callback is process-global in MuJoCo; an MjData whose userdata does not carry
 * this layout's mark (any other model, or this one before the plant arms it) is left alone.
 */
#include <math.h>

#include <mujoco/mujoco.h>

/* d->userdata, in doubles: a header, then five arrays of nu values each */
#define FK_SERVO_MARK 0    /* FK_SERVO_MARK_VALUE when armed */
#define FK_SERVO_SUBSTEP 1 /* substeps done this period (the callback counts them) */
#define FK_SERVO_NSUB 2    /* substeps per period, n */
#define FK_SERVO_NU 3      /* actuators, nu */
#define FK_SERVO_HEAD 4    /* then prev[nu], ref[nu], feed[nu], limit[nu], saturated[nu] */
#define FK_SERVO_MARK_VALUE 46553.0

int fuzzkit_servo_mj_version(void);
int fuzzkit_servo_mj_version(void)
{
    return mjVERSION_HEADER;
}

void fuzzkit_servo_ramp(const mjModel *m, mjData *d);
void fuzzkit_servo_ramp(const mjModel *m, mjData *d)
{
    mjtNum *u = d->userdata;
    const mjtNum *prev, *ref, *feed, *limit;
    mjtNum *saturated;
    double s, n;
    int i, nu;

    if (m->nuserdata < FK_SERVO_HEAD || u[FK_SERVO_MARK] != FK_SERVO_MARK_VALUE) {
        return;
    }
    nu = m->nu;
    if (u[FK_SERVO_NU] != (double)nu || m->nuserdata < FK_SERVO_HEAD + 5 * nu) {
        return;
    }
    s = u[FK_SERVO_SUBSTEP] + 1.0;
    n = u[FK_SERVO_NSUB];
    u[FK_SERVO_SUBSTEP] = s;
    prev = u + FK_SERVO_HEAD;
    ref = prev + nu;
    feed = ref + nu;
    limit = feed + nu;
    saturated = u + FK_SERVO_HEAD + 4 * nu;
    for (i = 0; i < nu; i++) {
        d->ctrl[i] = prev[i] + (s / n) * (ref[i] - prev[i]) + feed[i];
        if (s > 1.0 && fabs(d->actuator_force[i]) >= 0.999 * limit[i]) {
            saturated[i] = 1.0;
        }
    }
}
