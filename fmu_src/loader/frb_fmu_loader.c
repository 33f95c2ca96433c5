/*
 * frb_fmu_loader: the FMI 2.0 binary of a frbmodel FMU in front of pythonfmu's own binary.
 *
 * pythonfmu's binary (kept next to this one as <modelIdentifier>.pythonfmu.so) runs the slave inside the
 * Python of the process that loads it. In a Python host that Python exists; a non-Python host (a C/C++ tool)
 * has none, and the binary then fails with undefined Py* symbols. This loader makes both work:
 *
 *  - Python already initialized in the process (Py_IsInitialized found and true): only forward the calls.
 *  - Otherwise, on the first fmi2Instantiate: read the Python description written at build time
 *    (<resources>/frb_python.cfg, or the file named by the environment variable FRB_FMU_PYTHON_CFG), load
 *    that libpython with RTLD_GLOBAL (extension modules and pythonfmu's binary resolve Py* from it), start
 *    the interpreter as that environment's own `python` would (program name = its executable, so a venv,
 *    conda env or system Python finds its own sys.path), in UTF-8 mode whatever the host's locale, without
 *    Python signal handlers, and with the host's environment and LC_CTYPE left as they were.
 *
 * Statuses: every call returns the worse of pythonfmu's status and the statuses the slave logged during the
 * call (see the comment above struct Instance), so a slave can refuse a call with fmi2Error or fmi2Discard.
 *
 * Exit: pythonfmu's binary (0.7.0, and its current source) keeps its interpreter guard in a static std::shared_ptr and also resets that
 * pointer from an ELF destructor. At exit() the static destructor runs first (it is an exit handler) and
 * frees the shared_ptr's control block; the ELF destructor then decrements a counter inside the freed block,
 * which corrupts glibc's free lists ("free(): corrupted unsorted chunks" at the next free, often in
 * libgfortran's exit handler). This loader therefore resets the guard itself through pythonfmu's exported
 * finalizePythonInterpreter() from an exit handler registered after pythonfmu's binary was loaded, i.e. run
 * before pythonfmu's static destructor. The interpreter this loader started is deliberately never finalized:
 * finalizing numpy/scipy/numba at process exit gains nothing and is not supported by them.
 *
 * No FMI or Python headers are needed: the FMI 2.0 co-simulation types are declared below and Python is
 * reached through dlsym. Built by frbmodel.cosim.loader.compile_loader:
 *   cc -shared -fPIC -O2 -fvisibility=hidden -o <modelIdentifier>.so frb_fmu_loader.c -ldl -lpthread
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <limits.h>
#include <locale.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <wchar.h>

/* ---- FMI 2.0 types (FMI 2.0 standard, section 2.1) ---- */
typedef void *fmi2Component;
typedef void *fmi2ComponentEnvironment;
typedef void *fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef char fmi2Byte;
typedef const char *fmi2String;
typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef enum { fmi2DoStepStatus, fmi2PendingStatus, fmi2LastSuccessfulTime, fmi2Terminated } fmi2StatusKind;
typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...);
typedef struct {
    fmi2CallbackLogger logger;
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(fmi2ComponentEnvironment, fmi2Status);
    fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

#define EXPORT __attribute__((visibility("default")))
#define CFG_NAME "frb_python.cfg"
#define CFG_ENV "FRB_FMU_PYTHON_CFG"

/* ---- the real (pythonfmu) binary ---- */
static struct {
    fmi2Component (*Instantiate)(fmi2String, fmi2Type, fmi2String, fmi2String, const fmi2CallbackFunctions *,
                                 fmi2Boolean, fmi2Boolean);
    void (*FreeInstance)(fmi2Component);
    fmi2Status (*SetupExperiment)(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean, fmi2Real);
    fmi2Status (*EnterInitializationMode)(fmi2Component);
    fmi2Status (*ExitInitializationMode)(fmi2Component);
    fmi2Status (*Terminate)(fmi2Component);
    fmi2Status (*Reset)(fmi2Component);
    fmi2Status (*GetReal)(fmi2Component, const fmi2ValueReference[], size_t, fmi2Real[]);
    fmi2Status (*GetInteger)(fmi2Component, const fmi2ValueReference[], size_t, fmi2Integer[]);
    fmi2Status (*GetBoolean)(fmi2Component, const fmi2ValueReference[], size_t, fmi2Boolean[]);
    fmi2Status (*GetString)(fmi2Component, const fmi2ValueReference[], size_t, fmi2String[]);
    fmi2Status (*SetReal)(fmi2Component, const fmi2ValueReference[], size_t, const fmi2Real[]);
    fmi2Status (*SetInteger)(fmi2Component, const fmi2ValueReference[], size_t, const fmi2Integer[]);
    fmi2Status (*SetBoolean)(fmi2Component, const fmi2ValueReference[], size_t, const fmi2Boolean[]);
    fmi2Status (*SetString)(fmi2Component, const fmi2ValueReference[], size_t, const fmi2String[]);
    fmi2Status (*GetFMUstate)(fmi2Component, fmi2FMUstate *);
    fmi2Status (*SetFMUstate)(fmi2Component, fmi2FMUstate);
    fmi2Status (*FreeFMUstate)(fmi2Component, fmi2FMUstate *);
    fmi2Status (*SerializedFMUstateSize)(fmi2Component, fmi2FMUstate, size_t *);
    fmi2Status (*SerializeFMUstate)(fmi2Component, fmi2FMUstate, fmi2Byte[], size_t);
    fmi2Status (*DeSerializeFMUstate)(fmi2Component, const fmi2Byte[], size_t, fmi2FMUstate *);
    fmi2Status (*GetDirectionalDerivative)(fmi2Component, const fmi2ValueReference[], size_t,
                                           const fmi2ValueReference[], size_t, const fmi2Real[], fmi2Real[]);
    fmi2Status (*SetRealInputDerivatives)(fmi2Component, const fmi2ValueReference[], size_t, const fmi2Integer[],
                                          const fmi2Real[]);
    fmi2Status (*GetRealOutputDerivatives)(fmi2Component, const fmi2ValueReference[], size_t, const fmi2Integer[],
                                           fmi2Real[]);
    fmi2Status (*DoStep)(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean);
    fmi2Status (*CancelStep)(fmi2Component);
    fmi2Status (*GetStatus)(fmi2Component, const fmi2StatusKind, fmi2Status *);
    fmi2Status (*GetRealStatus)(fmi2Component, const fmi2StatusKind, fmi2Real *);
    fmi2Status (*GetIntegerStatus)(fmi2Component, const fmi2StatusKind, fmi2Integer *);
    fmi2Status (*GetBooleanStatus)(fmi2Component, const fmi2StatusKind, fmi2Boolean *);
    fmi2Status (*GetStringStatus)(fmi2Component, const fmi2StatusKind, fmi2String *);
    void (*finalizePythonInterpreter)(void);
} real;

static pthread_mutex_t load_lock = PTHREAD_MUTEX_INITIALIZER;
static int loaded;              /* the real binary is loaded and its functions resolved */
static char load_error[3 * PATH_MAX + 256];

typedef struct {
    char libpython[PATH_MAX], executable[PATH_MAX], home[PATH_MAX], path[8 * PATH_MAX];
} PythonConfig;

static int fail(const char *fmt, const char *a, const char *b) {
    snprintf(load_error, sizeof load_error, fmt, a ? a : "", b ? b : "");
    return -1;
}

/* The folder of this shared object (dladdr on one of our own functions). */
static int own_folder(char *out, size_t n) {
    Dl_info info;
    char *slash;
    if (!dladdr((void *)&own_folder, &info) || !info.dli_fname) return fail("cannot locate the loader itself", 0, 0);
    if (!realpath(info.dli_fname, out)) snprintf(out, n, "%s", info.dli_fname);
    slash = strrchr(out, '/');
    if (!slash) return fail("cannot locate the loader itself", 0, 0);
    *slash = '\0';
    return 0;
}

/* fmuResourceLocation "file:///a/b%20c" -> "/a/b c"; NULL/empty -> <binary folder>/../../resources */
static void resources_folder(const char *uri, char *out, size_t n) {
    size_t k = 0;
    if (!uri || !*uri) {
        char dir[PATH_MAX];
        if (own_folder(dir, sizeof dir) == 0) snprintf(out, n, "%s/../../resources", dir);
        else out[0] = '\0';
        return;
    }
    if (strncmp(uri, "file://", 7) == 0) uri += 7;
    else if (strncmp(uri, "file:", 5) == 0) uri += 5;
    if (strncmp(uri, "localhost/", 10) == 0) uri += 9;
    for (; *uri && k + 1 < n; ++uri) {
        unsigned int c;
        if (uri[0] == '%' && sscanf(uri + 1, "%2x", &c) == 1) {
            out[k++] = (char)c;
            uri += 2;
        } else {
            out[k++] = *uri;
        }
    }
    out[k] = '\0';
}

static void strip(char *s) {
    size_t n = strlen(s);
    while (n && (s[n - 1] == '\n' || s[n - 1] == '\r' || s[n - 1] == ' ' || s[n - 1] == '\t')) s[--n] = '\0';
}

/* Lines "key = value"; '#' starts a comment line. Keys: libpython, executable, home, path. */
static int read_config(const char *file, PythonConfig *cfg) {
    static char line[8 * PATH_MAX + 64]; /* static: host threads may have small stacks (called under load_lock) */
    FILE *f = fopen(file, "r");
    memset(cfg, 0, sizeof *cfg);
    if (!f) return fail("cannot read the Python description %s%s (rebuild the FMU with `frb build-fmus`, or set "
                        CFG_ENV " to such a file)", file, "");
    while (fgets(line, sizeof line, f)) {
        char *eq = strchr(line, '='), *key = line, *value;
        if (line[0] == '#' || !eq) continue;
        *eq = '\0';
        value = eq + 1;
        strip(key);
        while (*value == ' ' || *value == '\t') ++value;
        strip(value);
        if (!strcmp(key, "libpython")) snprintf(cfg->libpython, sizeof cfg->libpython, "%s", value);
        else if (!strcmp(key, "executable")) snprintf(cfg->executable, sizeof cfg->executable, "%s", value);
        else if (!strcmp(key, "home")) snprintf(cfg->home, sizeof cfg->home, "%s", value);
        else if (!strcmp(key, "path")) snprintf(cfg->path, sizeof cfg->path, "%s", value);
    }
    fclose(f);
    if (!cfg->libpython[0]) return fail("%s: no 'libpython = ...' line%s", file, "");
    return 0;
}

/* setenv/unsetenv with the previous value kept for restore_vars */
typedef struct {
    const char *name;
    char *old;
} SavedVar;

static void set_var(SavedVar *v, const char *name, const char *value) {
    const char *old = getenv(name);
    v->name = name;
    v->old = old ? strdup(old) : NULL;
    if (value) setenv(name, value, 1);
    else unsetenv(name);
}

static void restore_vars(SavedVar *v, int n) {
    for (int i = 0; i < n; ++i) {
        if (v[i].old) setenv(v[i].name, v[i].old, 1);
        else unsetenv(v[i].name);
        free(v[i].old);
    }
}

/* Start the interpreter described by cfg (libpython already loaded with RTLD_GLOBAL as `lib`). */
static int start_python(void *lib, const PythonConfig *cfg) {
    void (*initialize)(int) = (void (*)(int))dlsym(lib, "Py_InitializeEx");
    void (*set_program_name)(const wchar_t *) = (void (*)(const wchar_t *))dlsym(lib, "Py_SetProgramName");
    wchar_t *(*decode)(const char *, size_t *) = (wchar_t * (*)(const char *, size_t *))dlsym(lib, "Py_DecodeLocale");
    void *(*save_thread)(void) = (void *(*)(void))dlsym(lib, "PyEval_SaveThread");
    int *utf8_mode = (int *)dlsym(lib, "Py_UTF8Mode"); /* Py_InitializeEx ignores PYTHONUTF8, reads this */
    SavedVar saved[4];
    int n = 0, by_executable = set_program_name && decode && cfg->executable[0];
    char *ctype = strdup(setlocale(LC_CTYPE, NULL));

    if (!initialize || !save_thread) {
        free(ctype);
        return fail("%s is not a usable libpython (Py_InitializeEx missing)%s", cfg->libpython, "");
    }
    /* The environment's own executable makes Python find its prefix, venv (pyvenv.cfg) and site-packages
       exactly as running that executable does; PYTHONHOME/PYTHONPATH of the host would override that. Without
       Py_SetProgramName (removed in a future Python) the recorded home and path are used instead. */
    if (by_executable) set_program_name(decode(cfg->executable, NULL)); /* static storage: never freed */
    set_var(&saved[n++], "PYTHONHOME", by_executable || !cfg->home[0] ? NULL : cfg->home);
    set_var(&saved[n++], "PYTHONPATH", by_executable || !cfg->path[0] ? NULL : cfg->path);
    set_var(&saved[n++], "PYTHONUTF8", "1");       /* independent of the host's locale (C/POSIX included) */
    if (utf8_mode) *utf8_mode = 1;
    set_var(&saved[n++], "PYTHONUNBUFFERED", "1"); /* nothing left in Python's buffers at exit (no finalize) */
    initialize(0); /* 0: no Python signal handlers in the host process */
    restore_vars(saved, n);
    if (ctype) setlocale(LC_CTYPE, ctype);
    free(ctype);
    save_thread(); /* release the GIL (pythonfmu takes it in every call); this thread keeps its thread state */
    return 0;
}

static int python_is_running(void) {
    int (*is_initialized)(void) = (int (*)(void))dlsym(RTLD_DEFAULT, "Py_IsInitialized");
    return is_initialized && is_initialized();
}

static int load_python(const char *resources) {
    static PythonConfig cfg; /* static: ~45 kB, and host threads may have small stacks (called under load_lock) */
    char file[PATH_MAX + 64];
    const char *env = getenv(CFG_ENV);
    void *lib;
    if (env && *env) snprintf(file, sizeof file, "%s", env);
    else snprintf(file, sizeof file, "%s/" CFG_NAME, resources);
    if (read_config(file, &cfg)) return -1;
    lib = dlopen(cfg.libpython, RTLD_NOW | RTLD_GLOBAL);
    if (!lib) return fail("cannot load the Python library named in the FMU's Python description: %s (%s)",
                          dlerror(), file);
    return start_python(lib, &cfg);
}

static void reset_pythonfmu_guard(void) {
    if (real.finalizePythonInterpreter) real.finalizePythonInterpreter();
}

#define RESOLVE(name) *(void **)(&real.name) = dlsym(lib, "fmi2" #name)

static int load_real(void) {
    char dir[PATH_MAX], file[2 * PATH_MAX];
    Dl_info info;
    const char *base, *dot;
    void *lib;
    if (own_folder(dir, sizeof dir)) return -1;
    dladdr((void *)&load_real, &info);
    base = strrchr(info.dli_fname, '/') ? strrchr(info.dli_fname, '/') + 1 : info.dli_fname;
    dot = strrchr(base, '.');
    snprintf(file, sizeof file, "%s/%.*s.pythonfmu.so", dir, (int)(dot ? dot - base : (long)strlen(base)), base);
    lib = dlopen(file, RTLD_NOW | RTLD_LOCAL);
    if (!lib) return fail("cannot load pythonfmu's binary: %s%s", dlerror(), "");
    RESOLVE(Instantiate); RESOLVE(FreeInstance); RESOLVE(SetupExperiment);
    RESOLVE(EnterInitializationMode); RESOLVE(ExitInitializationMode); RESOLVE(Terminate); RESOLVE(Reset);
    RESOLVE(GetReal); RESOLVE(GetInteger); RESOLVE(GetBoolean); RESOLVE(GetString);
    RESOLVE(SetReal); RESOLVE(SetInteger); RESOLVE(SetBoolean); RESOLVE(SetString);
    RESOLVE(GetFMUstate); RESOLVE(SetFMUstate); RESOLVE(FreeFMUstate); RESOLVE(SerializedFMUstateSize);
    RESOLVE(SerializeFMUstate); RESOLVE(DeSerializeFMUstate); RESOLVE(GetDirectionalDerivative);
    RESOLVE(SetRealInputDerivatives); RESOLVE(GetRealOutputDerivatives); RESOLVE(DoStep); RESOLVE(CancelStep);
    RESOLVE(GetStatus); RESOLVE(GetRealStatus); RESOLVE(GetIntegerStatus); RESOLVE(GetBooleanStatus);
    RESOLVE(GetStringStatus);
    *(void **)(&real.finalizePythonInterpreter) = dlsym(lib, "finalizePythonInterpreter");
    if (!real.Instantiate || !real.FreeInstance)
        return fail("pythonfmu's binary %s lacks fmi2Instantiate or fmi2FreeInstance%s", file, "");
    /* registered after pythonfmu's binary registered its static destructors: runs before them at exit */
    atexit(reset_pythonfmu_guard);
    return 0;
}

/* ---- host threads without a Python thread state ----
 * pythonfmu's binary takes the GIL with PyGILState_Ensure in every call. From a host thread Python never saw
 * (libcosim's workers, a C tool's thread pool) that creates a thread state and destroys it again at the end of
 * every call (~1 ms). The loader gives such a thread a thread state of its own once, at its first call, and keeps
 * it (PyGILState_Ensure, then PyEval_SaveThread: the GIL is released, the state stays with the thread), so that
 * pythonfmu's calls from it only take and release the GIL. Threads that have a state (Python hosts, the thread
 * that started Python) are left alone. */
static void *(*this_thread_state)(void);
static int (*gil_ensure)(void);
static void *(*gil_save)(void);
static __thread int thread_adopted;

static void resolve_thread_api(void) {
    *(void **)(&this_thread_state) = dlsym(RTLD_DEFAULT, "PyGILState_GetThisThreadState");
    *(void **)(&gil_ensure) = dlsym(RTLD_DEFAULT, "PyGILState_Ensure");
    *(void **)(&gil_save) = dlsym(RTLD_DEFAULT, "PyEval_SaveThread");
}

static void adopt_thread(void) {
    if (thread_adopted) return;
    thread_adopted = 1;
    if (!this_thread_state || !gil_ensure || !gil_save || this_thread_state()) return;
    gil_ensure();
    gil_save();
}

static int ensure_loaded(const char *resource_uri) {
    char resources[PATH_MAX + 32];
    int rc = 0;
    pthread_mutex_lock(&load_lock);
    if (!loaded) {
        resources_folder(resource_uri, resources, sizeof resources);
        if (!python_is_running()) rc = load_python(resources);
        if (rc == 0) rc = load_real();
        if (rc == 0) resolve_thread_api();
        loaded = rc == 0;
    }
    pthread_mutex_unlock(&load_lock);
    if (rc == 0) adopt_thread();
    return rc;
}


/* ---- one host instance: pythonfmu's instance plus the host's callbacks and logging settings ----
 * pythonfmu's binary returns fmi2OK, fmi2Discard (do_step returned False) or fmi2Fatal (a Python exception),
 * never fmi2Warning or fmi2Error. The frbmodel slaves log every refusal with the status the call must return;
 * pythonfmu hands those messages to the logger callback at the end of the call. The loader therefore gives
 * pythonfmu its own logger (always on), returns the worst of pythonfmu's status and the statuses logged during
 * the call, and passes each message on to the host's logger: a message with a status above fmi2OK (the reason
 * of a warning, a discarded step, a refused call) always, as the Modelica Reference FMUs log errors whatever
 * loggingOn says, until the host switches logging off with fmi2SetDebugLogging(fmi2False, 0, NULL); an fmi2OK
 * message when the host's settings (fmi2Instantiate loggingOn, fmi2SetDebugLogging categories) let it through.
 * (pythonfmu itself drops every message when loggingOn is fmi2False: a host that instantiates with logging off,
 * as most do, would see Discard and Error without a reason.) The FMU's resources/frb_status_from_log tells the
 * slaves that their logged statuses are returned. */
typedef struct {
    fmi2Component real;          /* pythonfmu's instance */
    fmi2CallbackFunctions host;  /* the host's callbacks */
    fmi2CallbackFunctions mine;  /* given to pythonfmu: relay() as logger, this instance as environment */
    int logging;                 /* the host's loggingOn */
    int reasons;                 /* pass messages above fmi2OK (off once the host switched all logging off) */
    size_t n_categories;         /* the host's categories (none: all) */
    char **categories;
    fmi2Status worst;            /* worst status logged during the current call */
} Instance;

static void clear_categories(Instance *in) {
    for (size_t i = 0; i < in->n_categories; ++i) free(in->categories[i]);
    free(in->categories);
    in->categories = NULL;
    in->n_categories = 0;
}

/* "logAll" (a category pythonfmu declares) names every category */
static int listed(const Instance *in, fmi2String category) {
    for (size_t i = 0; i < in->n_categories; ++i)
        if (!strcmp(in->categories[i], "logAll") || !strcmp(in->categories[i], category ? category : "")) return 1;
    return 0;
}

/* a category the host named follows its on/off; else a reason (status above fmi2OK) unless the host switched all
   logging off; else an fmi2OK message when the host's logging is on for all categories */
static int message_shown(const Instance *in, fmi2Status status, fmi2String category) {
    if (in->n_categories && listed(in, category)) return in->logging;
    if (status > fmi2OK && status != fmi2Pending && in->reasons) return 1;
    return in->logging && in->n_categories == 0;
}

/* pythonfmu passes each message as the format string without arguments. It is passed on as a format string
   without arguments too, each '%' doubled: a host that formats (as the standard asks) prints the message, and a
   logger that cannot read variadic arguments (a Python ctypes callback without a formatting proxy) gets the whole
   text, not a bare "%s" */
static void relay(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                  fmi2String message, ...) {
    Instance *in = (Instance *)env;
    const char *text = message ? message : "";
    size_t n = 0, percents = 0;
    char *escaped;
    if (status != fmi2Pending && status > in->worst) in->worst = status;
    if (!in->host.logger || !message_shown(in, status, category)) return;
    for (const char *p = text; *p; ++p, ++n) percents += *p == '%';
    if (!percents) {
        in->host.logger(in->host.componentEnvironment, name, status, category, text);
        return;
    }
    escaped = (char *)malloc(n + percents + 1);
    if (!escaped) {  /* out of memory: the message as an argument (a formatting host still prints it) */
        in->host.logger(in->host.componentEnvironment, name, status, category, "%s", text);
        return;
    }
    for (char *q = escaped; ; ++text) {
        if (*text == '%') *q++ = '%';
        if (!(*q++ = *text)) break;
    }
    in->host.logger(in->host.componentEnvironment, name, status, category, escaped);
    free(escaped);
}

static void relay_step_finished(fmi2ComponentEnvironment env, fmi2Status status) {
    Instance *in = (Instance *)env;
    if (in->host.stepFinished) in->host.stepFinished(in->host.componentEnvironment, status);
}

static fmi2Status worse(fmi2Status returned, fmi2Status logged) {
    return logged > returned && returned != fmi2Pending ? logged : returned;
}

/* ---- exported FMI 2.0 co-simulation functions ---- */
EXPORT const char *fmi2GetTypesPlatform(void) { return "default"; }
EXPORT const char *fmi2GetVersion(void) { return "2.0"; }

EXPORT fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String resources,
                                     const fmi2CallbackFunctions *cb, fmi2Boolean visible, fmi2Boolean logging) {
    Instance *in;
    if (ensure_loaded(resources)) {
        if (cb && cb->logger) cb->logger(cb->componentEnvironment, name, fmi2Fatal, "logStatusFatal", "%s",
                                         load_error);
        else fprintf(stderr, "%s: %s\n", name ? name : "FMU", load_error);
        return NULL;
    }
    in = (Instance *)calloc(1, sizeof *in);
    if (!in) return NULL;
    if (cb) in->host = *cb;
    in->logging = logging;
    in->reasons = 1;
    in->mine.logger = relay;
    in->mine.allocateMemory = cb ? cb->allocateMemory : NULL;
    in->mine.freeMemory = cb ? cb->freeMemory : NULL;
    in->mine.stepFinished = cb && cb->stepFinished ? relay_step_finished : NULL;
    in->mine.componentEnvironment = in;
    in->real = real.Instantiate(name, type, guid, resources, &in->mine, visible, 1);
    if (!in->real) {
        free(in);
        return NULL;
    }
    return in;
}

EXPORT void fmi2FreeInstance(fmi2Component c) {
    Instance *in = (Instance *)c;
    if (!loaded || !in) return;
    adopt_thread();
    real.FreeInstance(in->real);
    clear_categories(in);
    free(in);
}

EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cat[]) {
    Instance *in = (Instance *)c;
    if (!loaded || !in) return fmi2Error;
    clear_categories(in);
    in->logging = on;
    if (!(n && cat)) in->reasons = on;  /* all categories: the reasons too; named ones: as listed */
    if (n && cat) {
        in->categories = (char **)calloc(n, sizeof(char *));
        if (!in->categories) return fmi2Error;
        in->n_categories = n;
        for (size_t i = 0; i < n; ++i)
            if (!(in->categories[i] = strdup(cat[i] ? cat[i] : ""))) {
                clear_categories(in);  /* (free(NULL) is a no-op for the ones not made) */
                return fmi2Error;
            }
    }
    return fmi2OK; /* pythonfmu's logger stays on: relay() filters */
}

/* fmi2<name>: the same call on pythonfmu's instance, returning the worse of its status and the logged ones */
#define FORWARD(name, params, args)                                \
    EXPORT fmi2Status fmi2##name params {                          \
        Instance *in = (Instance *)c;                              \
        fmi2Status returned;                                       \
        if (!loaded || !in || !real.name) return fmi2Error;        \
        adopt_thread();                                            \
        in->worst = fmi2OK;                                        \
        returned = real.name args;                                 \
        return worse(returned, in->worst);                         \
    }

typedef const fmi2ValueReference *VRs;
#define R in->real
FORWARD(SetupExperiment, (fmi2Component c, fmi2Boolean td, fmi2Real tol, fmi2Real t0, fmi2Boolean sd, fmi2Real t1),
        (R, td, tol, t0, sd, t1))
FORWARD(EnterInitializationMode, (fmi2Component c), (R))
FORWARD(ExitInitializationMode, (fmi2Component c), (R))
FORWARD(Terminate, (fmi2Component c), (R))
FORWARD(Reset, (fmi2Component c), (R))
FORWARD(GetReal, (fmi2Component c, VRs vr, size_t n, fmi2Real v[]), (R, vr, n, v))
FORWARD(GetInteger, (fmi2Component c, VRs vr, size_t n, fmi2Integer v[]), (R, vr, n, v))
FORWARD(GetBoolean, (fmi2Component c, VRs vr, size_t n, fmi2Boolean v[]), (R, vr, n, v))
FORWARD(GetString, (fmi2Component c, VRs vr, size_t n, fmi2String v[]), (R, vr, n, v))
FORWARD(SetReal, (fmi2Component c, VRs vr, size_t n, const fmi2Real v[]), (R, vr, n, v))
FORWARD(SetInteger, (fmi2Component c, VRs vr, size_t n, const fmi2Integer v[]), (R, vr, n, v))
FORWARD(SetBoolean, (fmi2Component c, VRs vr, size_t n, const fmi2Boolean v[]), (R, vr, n, v))
FORWARD(SetString, (fmi2Component c, VRs vr, size_t n, const fmi2String v[]), (R, vr, n, v))

/* FMI 2.0: on entry to fmi2GetFMUstate a non-NULL *s is a state returned before and not freed since, which the FMU
   may reuse. pythonfmu overwrites *s and leaks that state (a host that reuses its state, one per instance, would
   leak one per call): it is freed here first. */
EXPORT fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) {
    Instance *in = (Instance *)c;
    fmi2Status returned;
    if (!loaded || !in || !real.GetFMUstate || !s) return fmi2Error;
    adopt_thread();
    in->worst = fmi2OK;
    if (*s) {
        returned = real.FreeFMUstate ? real.FreeFMUstate(R, s) : fmi2Error;
        if (returned > fmi2Warning) return worse(returned, in->worst);
        *s = NULL;
    }
    returned = real.GetFMUstate(R, s);
    return worse(returned, in->worst);
}
FORWARD(SetFMUstate, (fmi2Component c, fmi2FMUstate s), (R, s))
FORWARD(FreeFMUstate, (fmi2Component c, fmi2FMUstate *s), (R, s))
FORWARD(SerializedFMUstateSize, (fmi2Component c, fmi2FMUstate s, size_t *n), (R, s, n))
FORWARD(SerializeFMUstate, (fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n), (R, s, b, n))
FORWARD(DeSerializeFMUstate, (fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s), (R, b, n, s))
FORWARD(GetDirectionalDerivative,
        (fmi2Component c, VRs u, size_t nu, VRs z, size_t nz, const fmi2Real dv[], fmi2Real dz[]),
        (R, u, nu, z, nz, dv, dz))
FORWARD(SetRealInputDerivatives, (fmi2Component c, VRs vr, size_t n, const fmi2Integer o[], const fmi2Real v[]),
        (R, vr, n, o, v))
FORWARD(GetRealOutputDerivatives, (fmi2Component c, VRs vr, size_t n, const fmi2Integer o[], fmi2Real v[]),
        (R, vr, n, o, v))
FORWARD(DoStep, (fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean keep), (R, t, h, keep))
FORWARD(CancelStep, (fmi2Component c), (R))
FORWARD(GetStatus, (fmi2Component c, const fmi2StatusKind k, fmi2Status *v), (R, k, v))
FORWARD(GetRealStatus, (fmi2Component c, const fmi2StatusKind k, fmi2Real *v), (R, k, v))
FORWARD(GetIntegerStatus, (fmi2Component c, const fmi2StatusKind k, fmi2Integer *v), (R, k, v))
FORWARD(GetBooleanStatus, (fmi2Component c, const fmi2StatusKind k, fmi2Boolean *v), (R, k, v))
FORWARD(GetStringStatus, (fmi2Component c, const fmi2StatusKind k, fmi2String *v), (R, k, v))
