/* A small crowd through the motion-lod C ABI.
 *
 * Usage: crowd MODEL.mlod [--dump]
 *
 * Loads a model file, places WALKERS characters at growing distances from the camera, lets the
 * model's distance policy choose each one's level of detail, and walks each for FRAMES frames at
 * FPS, chaining gait cycles: when a cycle ends, the walker's root moves by the cycle's root motion
 * and the next cycle is prepared. Every frame evaluates the pose and the joint transforms into
 * arrays owned here. It prints a summary; with --dump it prints every pose, transform and root
 * position as the bits of each float (hexadecimal), which the crate's test compares with the Rust
 * API bit for bit.
 *
 * Build (from the workspace root, after `cargo build --release -p motion-lod-ffi`):
 *   cc crates/motion-lod-ffi/examples/crowd.c -I crates/motion-lod-ffi/include \
 *      target/release/libmotion_lod_ffi.a -lm -lpthread -ldl -o crowd
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "motion_lod.h"

enum { WALKERS = 6, FRAMES = 45 };
static const double FPS = 30.0;

/* Prints the call's failure and exits. */
static void check(MlodStatus status, const char *what) {
    if (status != MLOD_STATUS_OK) {
        fprintf(stderr, "%s failed (status %d): %s\n", what, (int)status, mlod_last_error());
        exit(1);
    }
}

static uint32_t bits(float v) {
    uint32_t u;
    memcpy(&u, &v, sizeof u);
    return u;
}

static void dump_floats(const char *tag, int walker, int frame, const float *v, size_t n) {
    printf("%s %d %d", tag, walker, frame);
    for (size_t i = 0; i < n; i++) printf(" %08x", bits(v[i]));
    printf("\n");
}

int main(int argc, char **argv) {
    if (argc < 2) {
        fprintf(stderr, "usage: %s MODEL.mlod [--dump]\n", argv[0]);
        return 2;
    }
    int dump = argc > 2 && strcmp(argv[2], "--dump") == 0;

    MlodModel *model = NULL;
    check(mlod_model_load(argv[1], &model), "mlod_model_load");
    size_t levels = 0, joints = 0, animated = 0, pose_len = 0;
    check(mlod_model_sizes(model, &levels, &joints, &animated, &pose_len), "mlod_model_sizes");
    MlodControls lo, hi;
    check(mlod_model_control_range(model, &lo, &hi), "mlod_model_control_range");
    if (!dump)
        printf("model: %zu accuracy levels, %zu joints (%zu animated), poses of %zu floats\n", levels,
               joints, animated,
               pose_len);

    float *pose = malloc(pose_len * sizeof *pose);
    MlodJointTransform *transforms = malloc(joints * sizeof *transforms);
    if (!pose || !transforms) return 1;

    for (int i = 0; i < WALKERS; i++) {
        /* Walker i: 3 m, 12 m, 48 m, ... from the camera; controls spread over the data's range. */
        float distance = 3.0f * powf(4.0f, (float)i);
        float u = (float)i / (float)(WALKERS - 1);
        MlodControls controls = {
            .dx = lo.dx + (hi.dx - lo.dx) * 0.5f,
            .dz = lo.dz + (hi.dz - lo.dz) * u,
            .turn = lo.turn + (hi.turn - lo.turn) * (1.0f - u),
            .height = lo.height + (hi.height - lo.height) * 0.5f,
        };
        MlodDetail detail;
        check(mlod_model_detail_at(model, distance, &detail), "mlod_model_detail_at");
        MlodWalker *walker = NULL;
        check(mlod_walker_new(model, &walker), "mlod_walker_new");
        MlodCycle cycle;
        check(mlod_walker_prepare(walker, model, &controls, detail, &cycle), "mlod_walker_prepare");

        /* The cycle's frame in the world: position (x, z) and heading (radians). */
        float root[3] = {0.0f, 0.0f, 0.0f};
        double t = 0.0;
        int cycles = 1;
        for (int f = 0; f < FRAMES; f++) {
            while (t >= cycle.duration_s) {
                t -= cycle.duration_s;
                float c = cosf(root[2]), s = sinf(root[2]);
                root[0] += c * cycle.dx + s * cycle.dz;
                root[1] += -s * cycle.dx + c * cycle.dz;
                root[2] += cycle.turn;
                check(mlod_walker_prepare(walker, model, &controls, detail, &cycle),
                      "mlod_walker_prepare");
                cycles++;
            }
            check(mlod_walker_pose(walker, model, t, pose, pose_len), "mlod_walker_pose");
            check(mlod_walker_joint_transforms(walker, model, transforms, joints),
                  "mlod_walker_joint_transforms");
            if (dump) {
                printf("D %d %d %u %u\n", i, f, detail.level, detail.joints);
                dump_floats("P", i, f, pose, pose_len);
                dump_floats("J", i, f, (const float *)transforms,
                            joints * (sizeof *transforms / sizeof(float)));
                dump_floats("R", i, f, root, 3);
            }
            t += 1.0 / FPS;
        }
        if (!dump)
            printf("walker %d at %6.1f m: level %u, %u joints, %d cycles, root at (%.2f, %.2f) m\n",
                   i, distance, detail.level, detail.joints, cycles, root[0], root[1]);
        mlod_walker_free(walker);
    }

    /* Errors are status codes with a message, never a crash. */
    MlodModel *bad = NULL;
    const uint8_t garbage[4] = {1, 2, 3, 4};
    MlodStatus status = mlod_model_from_bytes(garbage, sizeof garbage, &bad);
    if (status != MLOD_STATUS_INVALID_MODEL || bad != NULL) {
        fprintf(stderr, "garbage bytes were not refused (status %d)\n", (int)status);
        return 1;
    }
    if (!dump) printf("garbage bytes refused: %s\n", mlod_last_error());

    free(pose);
    free(transforms);
    mlod_model_free(model);
    return 0;
}
