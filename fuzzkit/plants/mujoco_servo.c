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
 * substep reached 99.9 % of their limit; the last substep's forces, computed after the callback's
 * last call, are marked by fuzzkit_servo_mark_last after mj_step.
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

/* Whether d's userdata carries this layout for m's actuators (armed by the plant). */
static int armed(const mjModel *m, const mjData *d)
{
    const mjtNum *u = d->userdata;
    return m->nuserdata >= FK_SERVO_HEAD && u[FK_SERVO_MARK] == FK_SERVO_MARK_VALUE &&
           u[FK_SERVO_NU] == (double)m->nu && m->nuserdata >= FK_SERVO_HEAD + 5 * m->nu;
}

/* The torque-limit test, defined once: mark every actuator whose force (the last step's) is at
 * 99.9 % of its limit. */
static void mark_saturated(const mjModel *m, mjData *d)
{
    int i, nu = m->nu;
    const mjtNum *limit = d->userdata + FK_SERVO_HEAD + 3 * nu;
    mjtNum *saturated = d->userdata + FK_SERVO_HEAD + 4 * nu;
    for (i = 0; i < nu; i++) {
        if (fabs(d->actuator_force[i]) >= 0.999 * limit[i]) {
            saturated[i] = 1.0;
        }
    }
}

void fuzzkit_servo_ramp(const mjModel *m, mjData *d);
void fuzzkit_servo_ramp(const mjModel *m, mjData *d)
{
    mjtNum *u = d->userdata;
    const mjtNum *prev, *ref, *feed;
    double s, n;
    int i, nu = m->nu;

    if (!armed(m, d)) {
        return;
    }
    s = u[FK_SERVO_SUBSTEP] + 1.0;
    n = u[FK_SERVO_NSUB];
    u[FK_SERVO_SUBSTEP] = s;
    if (s > 1.0) {
        mark_saturated(m, d); /* the previous substep's forces */
    }
    prev = u + FK_SERVO_HEAD;
    ref = prev + nu;
    feed = ref + nu;
    for (i = 0; i < nu; i++) {
        d->ctrl[i] = prev[i] + (s / n) * (ref[i] - prev[i]) + feed[i];
    }
}

/* After a period's last substep: its forces, which the callback (run before them) cannot see. */
void fuzzkit_servo_mark_last(const mjModel *m, mjData *d);
void fuzzkit_servo_mark_last(const mjModel *m, mjData *d)
{
    if (armed(m, d)) {
        mark_saturated(m, d);
    }
}

/* Two helpers for a loop compiled around MuJoCo (fuzzkit/studies/compiled/mujoco_run.py), so
 * that a period needs no Python: */

/* n physics steps (the callback ramps the controls), the last one's torque limits marked;
 * returns how many times MuJoCo warned of a bad acceleration (mjWARN_BADQACC: the simulation
 * diverged and MuJoCo reset it) during them. */
int fuzzkit_mj_steps(const mjModel *m, mjData *d, int n);
int fuzzkit_mj_steps(const mjModel *m, mjData *d, int n)
{
    int before = d->warning[mjWARN_BADQACC].number;
    int k;
    for (k = 0; k < n; k++) {
        mj_step(m, d);
    }
    fuzzkit_servo_mark_last(m, d);
    return d->warning[mjWARN_BADQACC].number - before;
}

/* The contact forces geom `tip` exerts on the scene, as MujocoArmPlant._contact_force sums them
 * (the same operations in the same order): the total into total[3] (world frame), each
 * contact's normal part into normals[3 k] and its point into points[3 k], for up to `most`
 * contacts; returns the number of contacts of `tip`. */
int fuzzkit_tool_contacts(const mjModel *m, const mjData *d, int tip, double *total,
                          double *normals, double *points, int most);
int fuzzkit_tool_contacts(const mjModel *m, const mjData *d, int tip, double *total,
                          double *normals, double *points, int most)
{
    mjtNum out[6];
    double by_tool[3], along;
    int i, j, count = 0;

    total[0] = total[1] = total[2] = 0.0;
    for (i = 0; i < d->ncon; i++) {
        const mjContact *c = d->contact + i;
        const mjtNum *f = c->frame; /* rows: normal, then the two tangents */
        if (c->geom[0] != tip && c->geom[1] != tip) {
            continue;
        }
        mj_contactForce(m, d, i, out);
        for (j = 0; j < 3; j++) {
            /* the force geom1 exerts on geom2, from the contact frame: frame^T out */
            double on_geom2 = f[j] * out[0] + f[3 + j] * out[1] + f[6 + j] * out[2];
            by_tool[j] = c->geom[0] == tip ? on_geom2 : -on_geom2;
        }
        along = f[0] * by_tool[0] + f[1] * by_tool[1] + f[2] * by_tool[2];
        for (j = 0; j < 3; j++) {
            total[j] += by_tool[j];
            if (count < most) {
                normals[3 * count + j] = f[j] * along;
                points[3 * count + j] = c->pos[j];
            }
        }
        count++;
    }
    return count;
}
