/* Times the exported controller's fmi2DoStep alone (plus setting inputs and reading outputs,
 * as any importer must): usage  harness LIB.so GUID INPUTS.bin N_IN VR_IN0 N_OUT VR_OUT0 H
 * INPUTS.bin: rows of N_IN doubles. Prints the per-step times in ns, one per line. */
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

typedef void *(*inst_t)(const char *, int, const char *, const char *, const void *, int, int);
typedef int (*setget_t)(void *, const unsigned int *, size_t, double *);
typedef int (*step_t)(void *, double, double, int);
typedef int (*init_t)(void *);

static void logger(void *env, const char *name, int status, const char *cat, const char *msg, ...) {
    (void)env; (void)name; (void)status; (void)cat; fprintf(stderr, "%s\n", msg);
}

int main(int argc, char **argv) {
    if (argc != 9) { fprintf(stderr, "usage: see source\n"); return 2; }
    void *lib = dlopen(argv[1], RTLD_NOW);
    if (!lib) { fprintf(stderr, "%s\n", dlerror()); return 2; }
    inst_t inst = (inst_t)dlsym(lib, "fmi2Instantiate");
    setget_t set = (setget_t)dlsym(lib, "fmi2SetReal"), get = (setget_t)dlsym(lib, "fmi2GetReal");
    step_t step = (step_t)dlsym(lib, "fmi2DoStep");
    init_t enter = (init_t)dlsym(lib, "fmi2EnterInitializationMode"), leave = (init_t)dlsym(lib, "fmi2ExitInitializationMode");
    int n_in = atoi(argv[4]), vr_in0 = atoi(argv[5]), n_out = atoi(argv[6]), vr_out0 = atoi(argv[7]);
    double h = atof(argv[8]);
    FILE *f = fopen(argv[3], "rb");
    if (!f) return 2;
    fseek(f, 0, SEEK_END);
    long rows = ftell(f) / (long)(sizeof(double) * n_in);
    fseek(f, 0, SEEK_SET);
    double *in = malloc(sizeof(double) * n_in * rows), out[64];
    if (fread(in, sizeof(double) * n_in, rows, f) != (size_t)rows) return 2;
    fclose(f);
    unsigned int vin[64], vout[64];
    for (int i = 0; i < n_in; i++) vin[i] = vr_in0 + i;
    for (int i = 0; i < n_out; i++) vout[i] = vr_out0 + i;
    void *cb[5] = {(void *)logger, (void *)calloc, (void *)free, NULL, NULL};
    void *c = inst("bench", 1, argv[2], "", cb, 0, 0);
    if (!c) { fprintf(stderr, "instantiate failed\n"); return 2; }
    enter(c); leave(c);
    for (long k = 0; k < rows; k++) {
        struct timespec a, b;
        clock_gettime(CLOCK_MONOTONIC, &a);
        set(c, vin, n_in, in + k * n_in);
        step(c, k * h, h, 1);
        get(c, vout, n_out, out);
        clock_gettime(CLOCK_MONOTONIC, &b);
        printf("%ld\n", (b.tv_sec - a.tv_sec) * 1000000000L + (b.tv_nsec - a.tv_nsec));
    }
    return 0;
}
