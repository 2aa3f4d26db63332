/* Plain single-threaded C reference of sfcb's Morton ordering (docs/design.md §3): centroids of the
 * corner nodes, one bounding cube over all nodes, 21-level (3D) keys with x in the lowest bit,
 * a stable LSD radix sort of (key, index) pairs, vertex renumbering by first use over each
 * element's full node list. Reads the binary dump written by sfcb's bench example:
 *   u64 nodes, u64 elements, u64 nodes_per_element, u64 corners, f64 xyz[nodes*3], u32 conn[...]
 * Prints the median time of the ordering core over REPS runs and an FNV-1a hash of the element
 * order and node numbering, which the bench compares with sfcb's.
 * Build: cc -O3 -march=native -o sfc_ref sfc_ref.c */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <time.h>

static uint64_t spread3(uint64_t v) {
    uint64_t x = v & 0x1fffff;
    x = (x | (x << 32)) & 0x001f00000000ffffULL;
    x = (x | (x << 16)) & 0x001f0000ff0000ffULL;
    x = (x | (x << 8)) & 0x100f00f00f00f00fULL;
    x = (x | (x << 4)) & 0x10c30c30c30c30c3ULL;
    x = (x | (x << 2)) & 0x1249249249249249ULL;
    return x;
}

typedef struct { uint64_t key; uint32_t idx; uint32_t pad; } pair_t;

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv) {
    if (argc < 2) { fprintf(stderr, "usage: sfc_ref DUMP [REPS] [LEVELS]\n"); return 2; }
    int reps = argc > 2 ? atoi(argv[2]) : 5;
    int levels = argc > 3 ? atoi(argv[3]) : 21;
    FILE *f = fopen(argv[1], "rb");
    if (!f) { perror(argv[1]); return 1; }
    uint64_t h[4];
    if (fread(h, 8, 4, f) != 4) { fprintf(stderr, "bad dump\n"); return 1; }
    uint64_t nn = h[0], ne = h[1], per = h[2], corners = h[3];
    double *xyz = malloc(nn * 3 * sizeof(double));
    uint32_t *conn = malloc(ne * per * sizeof(uint32_t));
    if (fread(xyz, sizeof(double), nn * 3, f) != nn * 3 || fread(conn, 4, ne * per, f) != ne * per) {
        fprintf(stderr, "short dump\n"); return 1;
    }
    fclose(f);
    pair_t *a = malloc(ne * sizeof(pair_t)), *b = malloc(ne * sizeof(pair_t));
    uint32_t *node_new = malloc(nn * 4);
    double *times = malloc(reps * sizeof(double));
    uint64_t hash = 0;
    for (int r = 0; r < reps; r++) {
        double t0 = now();
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (uint64_t i = 0; i < nn; i++)
            for (int d = 0; d < 3; d++) {
                double v = xyz[i * 3 + d];
                if (v < lo[d]) lo[d] = v;
                if (v > hi[d]) hi[d] = v;
            }
        double side = 0;
        for (int d = 0; d < 3; d++) if (hi[d] - lo[d] > side) side = hi[d] - lo[d];
        double cells = (double)(1ULL << levels);
        uint64_t maxq = (1ULL << levels) - 1;
        for (uint64_t e = 0; e < ne; e++) {
            double c[3] = {0, 0, 0};
            for (uint64_t k = 0; k < corners; k++)
                for (int d = 0; d < 3; d++) c[d] += xyz[(uint64_t)conn[e * per + k] * 3 + d];
            uint64_t key = 0;
            for (int d = 0; d < 3; d++) {
                c[d] /= (double)corners;
                uint64_t q = 0;
                if (side > 0) {
                    double t = (c[d] - lo[d]) / side * cells;
                    q = t <= 0 ? 0 : (uint64_t)floor(t);
                    if (q > maxq) q = maxq;
                }
                key |= spread3(q) << d;
            }
            a[e].key = key; a[e].idx = (uint32_t)e;
        }
        /* Stable LSD radix sort by key, 8 bits a pass; passes where every key has the same
         * byte are skipped. */
        for (int shift = 0; shift < 64; shift += 8) {
            uint64_t count[256] = {0};
            for (uint64_t i = 0; i < ne; i++) count[(a[i].key >> shift) & 255]++;
            int skip = 0;
            for (int k = 0; k < 256; k++) if (count[k] == ne) skip = 1;
            if (skip) continue;
            uint64_t sum = 0;
            for (int k = 0; k < 256; k++) { uint64_t c = count[k]; count[k] = sum; sum += c; }
            for (uint64_t i = 0; i < ne; i++) b[count[(a[i].key >> shift) & 255]++] = a[i];
            pair_t *t = a; a = b; b = t;
        }
        memset(node_new, 0xff, nn * 4);
        uint32_t next = 0;
        for (uint64_t i = 0; i < ne; i++) {
            const uint32_t *el = conn + (uint64_t)a[i].idx * per;
            for (uint64_t k = 0; k < per; k++)
                if (node_new[el[k]] == 0xffffffffu) node_new[el[k]] = next++;
        }
        for (uint64_t v = 0; v < nn; v++) if (node_new[v] == 0xffffffffu) node_new[v] = next++;
        times[r] = now() - t0;
        hash = 1469598103934665603ULL;
        for (uint64_t i = 0; i < ne; i++) { hash ^= a[i].idx; hash *= 1099511628211ULL; }
        for (uint64_t v = 0; v < nn; v++) { hash ^= node_new[v]; hash *= 1099511628211ULL; }
    }
    qsort(times, reps, sizeof(double), cmp_double);
    printf("%.6f %016llx\n", times[reps / 2], (unsigned long long)hash);
    return 0;
}
