/* A driver for the CANopen fuzz target (co_fuzz.c) without libFuzzer, for gcc builds and CI:
 * inputs are the target's seeds (co_fuzz_seed) mutated - bytes flipped, chunks inserted, deleted
 * or spliced from another seed, random operations appended - or purely random, from a fixed
 * seed, until a budget of delivered frames is spent. A crash is the sanitizers' abort (the run
 * exits non-zero); a clean run prints the counts.
 *   co_fuzz [--frames N] [--seed S] [--write-seeds DIR] [--replay FILE] [--quiet]
 * A crashing input is saved to co_fuzz_crash.bin (the current directory) for --replay. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <time.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
size_t co_fuzz_seed(int k, uint8_t *buf, size_t cap);
extern uint64_t co_fuzz_frames;
extern uint64_t co_fuzz_reached[8];

static uint64_t rng_state;
static const uint8_t *cur_in;   /* the input being run, saved if it crashes */
static size_t cur_len;

static void save_crash(int sig)
{
    (void)sig;
    FILE *f = fopen("co_fuzz_crash.bin", "wb");
    if (f != NULL) {
        fwrite(cur_in, 1, cur_len, f);
        fclose(f);
        fprintf(stderr, "co_fuzz: the input is in co_fuzz_crash.bin (%zu bytes); replay: co_fuzz --replay co_fuzz_crash.bin\n",
                cur_len);
    }
    signal(SIGABRT, SIG_DFL);
    abort();
}

static int run(const uint8_t *in, size_t n)
{
    cur_in = in;
    cur_len = n;
    return LLVMFuzzerTestOneInput(in, n);
}

static uint64_t rnd(void)   /* splitmix64 */
{
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

#define MAXLEN 2048u
#define NSEEDS 8

static uint8_t seeds[NSEEDS][MAXLEN];
static size_t seed_len[NSEEDS];
static int n_seeds;

static size_t mutate(uint8_t *b, size_t n)
{
    const int edits = 1 + (int)(rnd() % 8u);
    for (int e = 0; e < edits; ++e) {
        switch (rnd() % 5u) {
        case 0:   /* flip bytes */
            if (n > 0) {
                b[rnd() % n] ^= (uint8_t)(1u << (rnd() % 8u));
            }
            break;
        case 1:   /* a random byte */
            if (n > 0) {
                b[rnd() % n] = (uint8_t)rnd();
            }
            break;
        case 2: {   /* insert random bytes */
            const size_t at = n > 0 ? rnd() % (n + 1) : 0, k = 1 + rnd() % 24u;
            if (n + k <= MAXLEN) {
                memmove(b + at + k, b + at, n - at);
                for (size_t j = 0; j < k; ++j) {
                    b[at + j] = (uint8_t)rnd();
                }
                n += k;
            }
            break;
        }
        case 3: {   /* delete a chunk */
            if (n > 1) {
                const size_t at = rnd() % n, k = 1 + rnd() % (n - at < 24u ? n - at : 24u);
                memmove(b + at, b + at + k, n - at - k);
                n -= k;
            }
            break;
        }
        default: {   /* splice another seed's tail */
            const int s = (int)(rnd() % (uint64_t)n_seeds);
            const size_t from = seed_len[s] > 0 ? rnd() % seed_len[s] : 0, at = n > 0 ? rnd() % n : 0;
            const size_t k = seed_len[s] - from;
            if (at + k <= MAXLEN) {
                memcpy(b + at, seeds[s] + from, k);
                n = at + k;
            }
            break;
        }
        }
    }
    return n;
}

int main(int argc, char **argv)
{
    uint64_t budget = 200000u, seed = 1u;
    const char *seed_dir = NULL;
    int quiet = 0;
    for (int k = 1; k < argc; ++k) {
        if (strcmp(argv[k], "--frames") == 0 && k + 1 < argc) {
            budget = strtoull(argv[++k], NULL, 10);
        } else if (strcmp(argv[k], "--seed") == 0 && k + 1 < argc) {
            seed = strtoull(argv[++k], NULL, 10);
        } else if (strcmp(argv[k], "--write-seeds") == 0 && k + 1 < argc) {
            seed_dir = argv[++k];
        } else if (strcmp(argv[k], "--replay") == 0 && k + 1 < argc) {
            static uint8_t rb[1u << 16];
            FILE *f = fopen(argv[++k], "rb");
            if (f == NULL) {
                perror(argv[k]);
                return 2;
            }
            const size_t n = fread(rb, 1, sizeof rb, f);
            fclose(f);
            LLVMFuzzerTestOneInput(rb, n);
            printf("co_fuzz: %s (%zu bytes) ran clean\n", argv[k], n);
            return 0;
        } else if (strcmp(argv[k], "--quiet") == 0) {
            quiet = 1;
        } else {
            fprintf(stderr, "usage: co_fuzz [--frames N] [--seed S] [--write-seeds DIR] [--replay FILE] [--quiet]\n");
            return 2;
        }
    }
    for (n_seeds = 0; n_seeds < NSEEDS; ++n_seeds) {
        seed_len[n_seeds] = co_fuzz_seed(n_seeds, seeds[n_seeds], MAXLEN);
        if (seed_len[n_seeds] == 0u) {
            break;
        }
    }
    if (seed_dir != NULL) {   /* a corpus for libFuzzer */
        for (int s = 0; s < n_seeds; ++s) {
            char path[512];
            snprintf(path, sizeof path, "%s/seed%d", seed_dir, s);
            FILE *f = fopen(path, "wb");
            if (f == NULL || fwrite(seeds[s], 1, seed_len[s], f) != seed_len[s]) {
                perror(path);
                return 1;
            }
            fclose(f);
        }
        printf("co_fuzz: %d seeds written to %s\n", n_seeds, seed_dir);
        return 0;
    }
    rng_state = seed;
    signal(SIGABRT, save_crash);
    static uint8_t in[MAXLEN];
    uint64_t inputs = 0;
    const clock_t t0 = clock();
    for (int s = 0; s < n_seeds; ++s) {   /* the seeds as they are */
        run(seeds[s], seed_len[s]);
        inputs++;
    }
    uint64_t next_report = budget / 10u;
    while (co_fuzz_frames < budget) {
        size_t n;
        if (rnd() % 4u == 0u) {   /* purely random */
            n = 16u + rnd() % 600u;
            for (size_t k = 0; k < n; ++k) {
                in[k] = (uint8_t)rnd();
            }
        } else {
            const int s = (int)(rnd() % (uint64_t)n_seeds);
            memcpy(in, seeds[s], seed_len[s]);
            n = mutate(in, seed_len[s]);
        }
        run(in, n);
        inputs++;
        if (!quiet && co_fuzz_frames >= next_report) {
            fprintf(stderr, "co_fuzz: %llu frames, %llu inputs\n", (unsigned long long)co_fuzz_frames,
                    (unsigned long long)inputs);
            next_report += budget / 10u;
        }
    }
    const double secs = (double)(clock() - t0) / CLOCKS_PER_SEC;
    printf("co_fuzz: %llu frames in %llu inputs (seed %llu), %.1f s, %.0f frames/s, no invariant violated\n",
           (unsigned long long)co_fuzz_frames, (unsigned long long)inputs, (unsigned long long)seed, secs,
           secs > 0 ? (double)co_fuzz_frames / secs : 0.0);
    printf("co_fuzz: inputs that reached: NMT operational %llu, 402 operation enabled %llu, drive RUN %llu, "
           "drive fault %llu, scope record %llu, NVM written %llu, RPDO applied %llu, TPDO2 remapped %llu\n",
           (unsigned long long)co_fuzz_reached[0], (unsigned long long)co_fuzz_reached[1],
           (unsigned long long)co_fuzz_reached[2], (unsigned long long)co_fuzz_reached[3],
           (unsigned long long)co_fuzz_reached[4], (unsigned long long)co_fuzz_reached[5],
           (unsigned long long)co_fuzz_reached[6], (unsigned long long)co_fuzz_reached[7]);
    return 0;
}
