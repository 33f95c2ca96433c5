/*
 * fmi2_host: a minimal FMI 2.0 co-simulation host in C, used by tests/test_c_host.py and
 * benchmarks/fmu_startup.py to run the frbmodel FMUs outside any Python process.
 *
 * It declares the few FMI 2.0 types and functions it uses itself (no FMI headers needed), loads
 * <dir>/binaries/linux64/<model>.so with dlopen, and runs:
 *   instantiate -> setupExperiment -> enterInitializationMode -> set parameters -> exitInitializationMode
 *   -> N x (set inputs, doStep, get outputs) -> terminate -> freeInstance.
 *
 * Usage:
 *   fmi2_host -d DIR -m MODEL_ID -g GUID -n STEPS -h STEP_SIZE_S
 *             [-r VR=VALUE]...      Real parameter set in initialization mode
 *             [-s VR=TEXT]...       String parameter set in initialization mode
 *             [-i FILE]             inputs: first line "VR VR ...", then one line of values per step
 *             [-o VR,VR,...]        outputs read after every step, printed as "t v v ..." (%.17g)
 *             [-t]                  print timings (seconds since start) to stderr
 *             [-l]                  loggingOn = fmi2True in fmi2Instantiate (the FMU's messages on stderr)
 *             [-u]                  unload the FMU binary (dlclose) after fmi2FreeInstance, as many hosts do
 *             [-T]                  make all FMI calls from a new thread (not the process's main thread)
 *             [-- next FMU options] further FMUs, run one after the other in the same process
 *
 * Output: "# MODEL_ID" before each FMU's output lines.
 * Exit status: 0 when every FMI call returned fmi2OK (or fmi2Warning), 1 otherwise, 2 on usage errors.
 */
#include <dlfcn.h>
#include <locale.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* ---- the FMI 2.0 declarations this host needs (FMI 2.0 standard, section 2.1) ---- */
typedef void *fmi2Component;
typedef void *fmi2ComponentEnvironment;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Boolean;
typedef const char *fmi2String;
typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...);
typedef struct {
    fmi2CallbackLogger logger;
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(fmi2ComponentEnvironment, fmi2Status);
    fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

typedef fmi2Component (*Instantiate)(fmi2String, fmi2Type, fmi2String, fmi2String, const fmi2CallbackFunctions *,
                                     fmi2Boolean, fmi2Boolean);
typedef fmi2Status (*SetupExperiment)(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean, fmi2Real);
typedef fmi2Status (*ComponentOnly)(fmi2Component);
typedef fmi2Status (*SetReal)(fmi2Component, const fmi2ValueReference *, size_t, const fmi2Real *);
typedef fmi2Status (*GetReal)(fmi2Component, const fmi2ValueReference *, size_t, fmi2Real *);
typedef fmi2Status (*SetString)(fmi2Component, const fmi2ValueReference *, size_t, const fmi2String *);
typedef fmi2Status (*DoStep)(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean);
typedef void (*FreeInstance)(fmi2Component);

#define MAX_VARS 256

static struct timespec t_start;

static double elapsed_s(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)(t.tv_sec - t_start.tv_sec) + 1e-9 * (double)(t.tv_nsec - t_start.tv_nsec);
}

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env;
    va_list ap;
    va_start(ap, message);
    fprintf(stderr, "[%s] status %d %s: ", instance ? instance : "?", (int)status, category ? category : "");
    vfprintf(stderr, message ? message : "", ap);
    fputc('\n', stderr);
    va_end(ap);
}

static void *must_sym(void *lib, const char *name) {
    void *f = dlsym(lib, name);
    if (!f) {
        fprintf(stderr, "fmi2_host: symbol %s not found: %s\n", name, dlerror());
        exit(1);
    }
    return f;
}

static int check(const char *what, fmi2Status s) {
    if (s == fmi2OK || s == fmi2Warning) return 0;
    fprintf(stderr, "fmi2_host: %s returned status %d\n", what, (int)s);
    return 1;
}

/* "VR=VALUE" -> vr and the text after '=' */
static int split_assignment(const char *arg, fmi2ValueReference *vr, const char **value) {
    const char *eq = strchr(arg, '=');
    if (!eq) return -1;
    *vr = (fmi2ValueReference)strtoul(arg, NULL, 10);
    *value = eq + 1;
    return 0;
}

static size_t parse_vr_list(char *text, fmi2ValueReference *vrs) {
    size_t n = 0;
    for (char *tok = strtok(text, ", \t\n"); tok && n < MAX_VARS; tok = strtok(NULL, ", \t\n"))
        vrs[n++] = (fmi2ValueReference)strtoul(tok, NULL, 10);
    return n;
}

typedef struct {
    const char *dir, *model, *guid, *input_file;
    long steps;
    double h;
    int timing, unload, logging, thread;
    size_t n_real, n_str, n_out;
    fmi2ValueReference real_vr[MAX_VARS], str_vr[MAX_VARS], out_vr[MAX_VARS];
    double real_val[MAX_VARS];
    fmi2String str_val[MAX_VARS];
} Options;

static int parse_options(int argc, char **argv, Options *o) {
    int c;
    const char *value;
    memset(o, 0, sizeof *o);
    o->steps = 1;
    o->h = 1e-5;
    while ((c = getopt(argc, argv, "d:m:g:n:h:r:s:i:o:tluT")) != -1) {
        switch (c) {
        case 'd': o->dir = optarg; break;
        case 'm': o->model = optarg; break;
        case 'g': o->guid = optarg; break;
        case 'n': o->steps = strtol(optarg, NULL, 10); break;
        case 'h': o->h = strtod(optarg, NULL); break;
        case 'i': o->input_file = optarg; break;
        case 'o': o->n_out = parse_vr_list(optarg, o->out_vr); break;
        case 't': o->timing = 1; break;
        case 'u': o->unload = 1; break;
        case 'l': o->logging = 1; break;
        case 'T': o->thread = 1; break;
        case 'r':
            if (o->n_real >= MAX_VARS || split_assignment(optarg, &o->real_vr[o->n_real], &value)) return -1;
            o->real_val[o->n_real++] = strtod(value, NULL);
            break;
        case 's':
            if (o->n_str >= MAX_VARS || split_assignment(optarg, &o->str_vr[o->n_str], &value)) return -1;
            o->str_val[o->n_str++] = value;
            break;
        default: return -1;
        }
    }
    return (o->dir && o->model && o->guid && o->steps > 0 && o->h > 0) ? 0 : -1;
}

/* Run one FMU through its whole life cycle (options o); returns 0 if every call succeeded. */
static int run_fmu(const Options *o) {
    char path[4096], resources[4096], line[65536];
    fmi2ValueReference in_vr[MAX_VARS];
    double in_val[MAX_VARS], out_val[MAX_VARS];
    size_t n_in = 0;
    FILE *inputs = NULL;
    int failed = 0;

    if (o->input_file) {
        inputs = fopen(o->input_file, "r");
        if (!inputs || !fgets(line, sizeof line, inputs)) {
            fprintf(stderr, "fmi2_host: cannot read the inputs file %s\n", o->input_file);
            return 2;
        }
        n_in = parse_vr_list(line, in_vr);
    }
    snprintf(path, sizeof path, "%s/binaries/linux64/%s.so", o->dir, o->model);
    snprintf(resources, sizeof resources, "file://%s/resources", o->dir);
    void *lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "fmi2_host: cannot load %s: %s\n", path, dlerror());
        return 1;
    }
    Instantiate instantiate = (Instantiate)must_sym(lib, "fmi2Instantiate");
    SetupExperiment setup = (SetupExperiment)must_sym(lib, "fmi2SetupExperiment");
    ComponentOnly enter_init = (ComponentOnly)must_sym(lib, "fmi2EnterInitializationMode");
    ComponentOnly exit_init = (ComponentOnly)must_sym(lib, "fmi2ExitInitializationMode");
    ComponentOnly terminate = (ComponentOnly)must_sym(lib, "fmi2Terminate");
    SetReal set_real = (SetReal)must_sym(lib, "fmi2SetReal");
    GetReal get_real = (GetReal)must_sym(lib, "fmi2GetReal");
    SetString set_string = (SetString)must_sym(lib, "fmi2SetString");
    DoStep do_step = (DoStep)must_sym(lib, "fmi2DoStep");
    FreeInstance free_instance = (FreeInstance)must_sym(lib, "fmi2FreeInstance");

    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2Component c = instantiate(o->model, fmi2CoSimulation, o->guid, resources, &cb, 0, o->logging);
    if (!c) {
        fprintf(stderr, "fmi2_host: fmi2Instantiate failed\n");
        return 1;
    }
    if (o->timing) fprintf(stderr, "timing %s instantiated_s %.6f\n", o->model, elapsed_s());
    failed |= check("fmi2SetupExperiment", setup(c, 0, 0.0, 0.0, 0, 0.0));
    failed |= check("fmi2EnterInitializationMode", enter_init(c));
    if (o->n_real) failed |= check("fmi2SetReal (parameters)", set_real(c, o->real_vr, o->n_real, o->real_val));
    if (o->n_str) failed |= check("fmi2SetString (parameters)", set_string(c, o->str_vr, o->n_str, o->str_val));
    failed |= check("fmi2ExitInitializationMode", exit_init(c));
    if (o->timing) fprintf(stderr, "timing %s initialized_s %.6f\n", o->model, elapsed_s());
    printf("# %s\n", o->model);
    for (long k = 0; k < o->steps && !failed; ++k) {
        double t = (double)k * o->h;
        if (inputs) {
            for (size_t j = 0; j < n_in; ++j) {
                if (fscanf(inputs, "%lf", &in_val[j]) != 1) {
                    fprintf(stderr, "fmi2_host: the inputs file ends before step %ld\n", k);
                    return 2;
                }
            }
            failed |= check("fmi2SetReal (inputs)", set_real(c, in_vr, n_in, in_val));
        }
        failed |= check("fmi2DoStep", do_step(c, t, o->h, 1));
        if (k == 0 && o->timing) fprintf(stderr, "timing %s first_step_s %.6f\n", o->model, elapsed_s());
        if (o->n_out) {
            failed |= check("fmi2GetReal", get_real(c, o->out_vr, o->n_out, out_val));
            printf("%.17g", t + o->h);
            for (size_t j = 0; j < o->n_out; ++j) printf(" %.17g", out_val[j]);
            putchar('\n');
        }
    }
    if (o->timing) fprintf(stderr, "timing %s stepped_s %.6f\n", o->model, elapsed_s());
    failed |= check("fmi2Terminate", terminate(c));
    free_instance(c);
    if (o->unload && dlclose(lib)) fprintf(stderr, "fmi2_host: dlclose failed: %s\n", dlerror());
    if (inputs) fclose(inputs);
    fflush(stdout);
    if (o->timing) fprintf(stderr, "timing %s freed_s %.6f\n", o->model, elapsed_s());
    return failed ? 1 : 0;
}

static void *run_in_thread(void *o) {
    static int rc;
    rc = run_fmu((const Options *)o);
    return &rc;
}

int main(int argc, char **argv) {
    static Options o;
    int rc = 0, start = 0;

    clock_gettime(CLOCK_MONOTONIC, &t_start);
    setlocale(LC_ALL, ""); /* the locale of the environment, as interactive tools do */
    /* FMU groups separated by "--" run one after the other in this process */
    while (start < argc && rc == 0) {
        int end = start + 1;
        while (end < argc && strcmp(argv[end], "--") != 0) ++end;
        char *first = argv[start];
        argv[start] = argv[0];
        optind = 0; /* glibc: restart getopt on the next argument vector */
        if (parse_options(end - start, argv + start, &o)) {
            fprintf(stderr, "usage: fmi2_host -d DIR -m MODEL_ID -g GUID -n STEPS -h STEP_S [-r VR=X] [-s VR=TEXT] "
                            "[-i INPUTS] [-o VR,VR] [-t] [-l] [-u] [-T] [-- next FMU ...]\n");
            return 2;
        }
        argv[start] = first;
        if (o.thread) {
            pthread_t th;
            void *res;
            pthread_create(&th, NULL, run_in_thread, &o);
            pthread_join(th, &res);
            rc = *(int *)res;
        } else {
            rc = run_fmu(&o);
        }
        start = end;
    }
    return rc;
}
