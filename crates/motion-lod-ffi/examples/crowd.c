/* A crowd of 1,000 walkers through the motion-lod C ABI, nothing computed here but the choice of
 * controls.
 *
 * Usage: crowd MODEL.mlod [--dump] [--no-foot-lock]
 *
 * Loads a model file and checks the library it linked, places WALKERS characters on a grid in
 * front of and behind a camera, and walks them for FRAMES frames at FPS. Every frame, each walker
 * asks the library for its level of detail from the camera (out of view: root only), and advances
 * by the frame's step with the controls and detail of its next cycle; the library chains the cycles
 * (the cycle frame moves by each cycle's root motion), plants the feet (foot lock) and reports the
 * root in the world. Each walker's controls change from cycle to cycle. The program then reads the
 * local joint rotations (for skinning) and the joint transforms into arrays owned here.
 *
 * It prints a summary. With --dump it prints, instead, every value of a subset of walkers and
 * frames as the bits of each float (hexadecimal), and for every walker a checksum of every value of
 * every frame; the crate's test computes the same walk through the Rust API and compares them bit
 * for bit. --no-foot-lock turns every walker's foot lock off.
 *
 * Build (from the workspace root, after `cargo build --release -p motion-lod-ffi`):
 *   cc crates/motion-lod-ffi/examples/crowd.c -I crates/motion-lod-ffi/include \
 *      target/release/libmotion_lod_ffi.a -lm -lpthread -ldl -o crowd
 */
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "motion_lod.h"

enum { WALKERS = 1000, COLUMNS = 40, FRAMES = 120, DUMP_EVERY_WALKER = 97, DUMP_EVERY_FRAME = 29 };
static const double FPS = 30.0;
/* Grid spacing (m) and the sphere around a walker's root that holds its body (m). */
static const float SPACING_M = 4.0f;
static const float RADIUS_M = 1.2f;

/* Prints the call's failure and exits. */
static void check(MlodStatus status, const char *what) {
    if (status != MLOD_STATUS_OK) {
        fprintf(stderr, "%s failed (status %d): %s\n", what, (int)status, mlod_last_error());
        exit(1);
    }
}

/* Walker i's controls for its cycle k: spread over the model's range, different every cycle. The
 * style weights the initializer leaves 0 ask for the data's own mix of styles (a model with
 * styles, mlod_model_style_count > 0, takes a weight per style instead, for example 1 for one). */
static MlodControls controls_for(const MlodControls *lo, const MlodControls *hi, int i,
                                 uint64_t k) {
    float u = (float)((i * 7 + (int)k * 3) % 11) / 10.0f;
    float v = (float)((i * 5 + (int)k * 2) % 7) / 6.0f;
    MlodControls c = {
        .dx = lo->dx + (hi->dx - lo->dx) * (0.25f + 0.5f * v),
        .dz = lo->dz + (hi->dz - lo->dz) * u,
        .turn = lo->turn + (hi->turn - lo->turn) * (1.0f - u),
        .height = lo->height + (hi->height - lo->height) * v,
    };
    return c;
}

static uint32_t bits(float v) {
    uint32_t u;
    memcpy(&u, &v, sizeof u);
    return u;
}

/* FNV-1a over 32-bit words. */
static uint64_t mix(uint64_t h, uint32_t word) {
    h ^= word;
    h *= 0x100000001b3ULL;
    return h;
}

static uint64_t mix_floats(uint64_t h, const float *v, size_t n) {
    for (size_t k = 0; k < n; k++) h = mix(h, bits(v[k]));
    return h;
}

static uint64_t mix_u64(uint64_t h, uint64_t v) {
    return mix(mix(h, (uint32_t)v), (uint32_t)(v >> 32));
}

static uint64_t mix_f64(uint64_t h, double v) {
    uint64_t u;
    memcpy(&u, &v, sizeof u);
    return mix_u64(h, u);
}

/* The state's values, in the order the dump and the checksum take them. */
static size_t state_words(const MlodWalkerState *s, uint32_t *out) {
    size_t n = 0;
    uint64_t t, d;
    memcpy(&t, &s->time_in_cycle_s, sizeof t);
    memcpy(&d, &s->cycle_duration_s, sizeof d);
    out[n++] = (uint32_t)t;
    out[n++] = (uint32_t)(t >> 32);
    out[n++] = (uint32_t)d;
    out[n++] = (uint32_t)(d >> 32);
    out[n++] = (uint32_t)s->cycle;
    out[n++] = (uint32_t)(s->cycle >> 32);
    const double doubles[6] = {s->root_position[0], s->root_position[1], s->root_position[2],
                               s->cycle_x, s->cycle_z, s->heading};
    for (int k = 0; k < 6; k++) {
        uint64_t u;
        memcpy(&u, &doubles[k], sizeof u);
        out[n++] = (uint32_t)u;
        out[n++] = (uint32_t)(u >> 32);
    }
    out[n++] = bits(s->root_rotation.x);
    out[n++] = bits(s->root_rotation.y);
    out[n++] = bits(s->root_rotation.z);
    out[n++] = bits(s->root_rotation.w);
    out[n++] = bits(s->body_scale);
    out[n++] = s->detail.level;
    out[n++] = s->detail.joints;
    out[n++] = s->cycles_begun;
    out[n++] = s->foot_locked ? 1u : 0u;
    return n;
}

static void dump_words(const char *tag, int walker, int frame, const uint32_t *v, size_t n) {
    printf("%s %d %d", tag, walker, frame);
    for (size_t k = 0; k < n; k++) printf(" %08x", v[k]);
    printf("\n");
}

static void dump_floats(const char *tag, int walker, int frame, const float *v, size_t n) {
    printf("%s %d %d", tag, walker, frame);
    for (size_t k = 0; k < n; k++) printf(" %08x", bits(v[k]));
    printf("\n");
}

int main(int argc, char **argv) {
    if (argc < 2) {
        fprintf(stderr, "usage: %s MODEL.mlod [--dump] [--no-foot-lock]\n", argv[0]);
        return 2;
    }
    bool dump = false, foot_lock = true;
    for (int a = 2; a < argc; a++) {
        if (strcmp(argv[a], "--dump") == 0) {
            dump = true;
        } else if (strcmp(argv[a], "--no-foot-lock") == 0) {
            foot_lock = false;
        } else {
            fprintf(stderr, "unknown option %s\n", argv[a]);
            return 2;
        }
    }

    /* The library this program linked must be the one its header describes. */
    if (mlod_abi_version() != MLOD_ABI_VERSION) {
        fprintf(stderr, "linked ABI %u, header ABI %u\n", mlod_abi_version(), MLOD_ABI_VERSION);
        return 1;
    }

    MlodModel *model = NULL;
    check(mlod_model_load(argv[1], &model), "mlod_model_load");
    size_t levels = 0, joints = 0, animated = 0, pose_len = 0;
    check(mlod_model_sizes(model, &levels, &joints, &animated, &pose_len), "mlod_model_sizes");
    MlodControls lo, hi;
    check(mlod_model_control_range(model, &lo, &hi), "mlod_model_control_range");
    /* The skeleton, as an engine binds its mesh to it: names, parents, rest offsets and rotations
     * (the offsets times a walker's body scale are its bones' local translations). */
    int32_t *parents = malloc(joints * sizeof *parents);
    MlodJointTransform *rest = malloc(joints * sizeof *rest);
    char top[64] = "";
    if (!parents || !rest) return 1;
    for (size_t j = 0; j < joints; j++) {
        char name[64];
        check(mlod_model_joint(model, j, name, sizeof name, NULL, &parents[j]), "mlod_model_joint");
        check(mlod_model_joint_rest(model, j, &rest[j]), "mlod_model_joint_rest");
        if (j == 0) strcpy(top, name);
    }
    if (!dump) {
        printf("motion-lod %s (ABI %u)\n", mlod_version(), mlod_abi_version());
        printf("model: %zu accuracy levels, %zu joints from %s (%zu animated), poses of %zu "
               "floats\n",
               levels, joints, top, animated, pose_len);
    }

    /* A camera 1.7 m above the ground, looking along +z over the crowd; walkers behind it, beside
     * its view or beyond its far distance are out of view. */
    const MlodCamera camera = {
        .position = {0.0, 1.7, -8.0},
        .direction = {0.0f, 0.0f, 1.0f},
        .fov_y = 1.0471976f, /* 60 degrees */
        .aspect = 16.0f / 9.0f,
        .image_height_px = 1080.0f,
        .near_m = 0.1f,
        .far_m = 90.0f,
    };
    const double dt = 1.0 / FPS;

    MlodWalker **walkers = calloc(WALKERS, sizeof *walkers);
    MlodWalkerState *states = calloc(WALKERS, sizeof *states);
    uint64_t *sums = calloc(WALKERS, sizeof *sums);
    MlodQuat *locals = malloc(joints * sizeof *locals);
    MlodJointTransform *transforms = malloc(joints * sizeof *transforms);
    uint32_t *words = malloc(7 * joints * sizeof *words + 64);
    if (!walkers || !states || !sums || !locals || !transforms || !words) return 1;

    /* Per detail (level, joints) and frame: how many walkers had it; visible, locked walkers. */
    size_t *histogram = calloc(levels * (animated + 1), sizeof *histogram);
    size_t visible_count = 0, locked_count = 0;
    if (!histogram) return 1;
    clock_t start = clock();

    for (int f = 0; f < FRAMES; f++) {
        for (int i = 0; i < WALKERS; i++) {
            MlodDetail detail;
            bool visible = false;
            if (f == 0) {
                /* Walker i starts on the grid, its detail from the camera at its start position. */
                float x = ((float)(i % COLUMNS) - 19.5f) * SPACING_M;
                float z = ((float)(i / COLUMNS) - 5.0f) * SPACING_M;
                float heading = (float)(i % 16) * 0.39269908f - 3.0f;
                check(mlod_model_detail_from_camera(model, &camera, x, 1.0f, z, RADIUS_M, &detail,
                                                    &visible),
                      "mlod_model_detail_from_camera");
                MlodControls first = controls_for(&lo, &hi, i, 0);
                check(mlod_walker_new(model, &walkers[i]), "mlod_walker_new");
                check(mlod_walker_set_foot_lock(walkers[i], foot_lock),
                      "mlod_walker_set_foot_lock");
                check(mlod_walker_start(walkers[i], model, &first, detail, x, z, heading,
                                        &states[i]),
                      "mlod_walker_start");
                sums[i] = 0xcbf29ce484222325ULL;
            } else {
                /* The detail for the walker's next cycle from where it is now, and that cycle's
                 * controls; the library uses them when the current cycle ends. */
                check(mlod_walker_detail_from_camera(walkers[i], model, &camera, RADIUS_M, &detail,
                                                     &visible),
                      "mlod_walker_detail_from_camera");
                MlodControls next = controls_for(&lo, &hi, i, states[i].cycle + 1);
                check(mlod_walker_advance(walkers[i], model, dt, &next, &detail, &states[i]),
                      "mlod_walker_advance");
            }
            const MlodWalkerState *s = &states[i];
            check(mlod_walker_local_rotations(walkers[i], model, locals, joints),
                  "mlod_walker_local_rotations");
            check(mlod_walker_joint_transforms(walkers[i], model, transforms, joints),
                  "mlod_walker_joint_transforms");

            histogram[s->detail.level * (animated + 1) + s->detail.joints]++;
            visible_count += visible;
            locked_count += s->foot_locked;

            uint64_t h = sums[i];
            h = mix(h, (uint32_t)f);
            h = mix(h, detail.level);
            h = mix(h, detail.joints);
            h = mix(h, visible ? 1u : 0u);
            size_t n = state_words(s, words);
            for (size_t k = 0; k < n; k++) h = mix(h, words[k]);
            h = mix_floats(h, (const float *)locals, 4 * joints);
            h = mix_floats(h, (const float *)transforms, 7 * joints);
            sums[i] = h;

            bool dumped_frame = f % DUMP_EVERY_FRAME == 0 || f == FRAMES - 1;
            if (dump && i % DUMP_EVERY_WALKER == 0 && dumped_frame) {
                printf("D %d %d %u %u %d\n", i, f, detail.level, detail.joints, visible ? 1 : 0);
                dump_words("S", i, f, words, n);
                dump_floats("L", i, f, (const float *)locals, 4 * joints);
                dump_floats("J", i, f, (const float *)transforms,
                            joints * (sizeof *transforms / sizeof(float)));
            }
        }
    }
    double seconds = (double)(clock() - start) / CLOCKS_PER_SEC;

    if (dump) {
        for (int i = 0; i < WALKERS; i++) {
            uint64_t h = mix_u64(sums[i], states[i].cycle);
            h = mix_f64(h, states[i].time_in_cycle_s);
            printf("H %d %llu %016llx\n", i, (unsigned long long)states[i].cycle,
                   (unsigned long long)h);
        }
    } else {
        size_t cycles = 0;
        for (int i = 0; i < WALKERS; i++) cycles += states[i].cycle;
        printf("walkers: %d for %d frames at %.0f fps, %zu cycles chained, %.2f us per "
               "walker-frame (with local rotations and transforms)\n",
               WALKERS, FRAMES, FPS, cycles, 1e6 * seconds / ((double)WALKERS * FRAMES));
        printf("in view: %.1f%% of walker-frames; feet locked: %.1f%%\n",
               100.0 * (double)visible_count / ((double)WALKERS * FRAMES),
               100.0 * (double)locked_count / ((double)WALKERS * FRAMES));
        for (size_t l = 0; l < levels; l++)
            for (size_t j = 0; j <= animated; j++) {
                size_t c = histogram[l * (animated + 1) + j];
                if (c > 0)
                    printf("detail level %zu, %2zu joints: %5.1f%% of walker-frames\n", l, j,
                           100.0 * (double)c / ((double)WALKERS * FRAMES));
            }
        const MlodWalkerState *s = &states[0];
        printf("walker 0: cycle %llu, root at (%.2f, %.2f, %.2f) m, heading %.2f rad\n",
               (unsigned long long)s->cycle, s->root_position[0], s->root_position[1],
               s->root_position[2], s->heading);
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

    for (int i = 0; i < WALKERS; i++) mlod_walker_free(walkers[i]);
    free(walkers);
    free(states);
    free(sums);
    free(locals);
    free(transforms);
    free(words);
    free(histogram);
    free(parents);
    free(rest);
    mlod_model_free(model);
    return 0;
}
