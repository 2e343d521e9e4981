/* SPDX-License-Identifier: MIT */
/* hal_dl.c: dlopen at first use (hal_dl.h): one load per library, every
 * symbol resolved at once so a wrong version fails here, not mid-scan. */
#include "hal_dl.h"
#include <dlfcn.h>
#include <stdio.h>

const char *hal_dl_strerror(int code)
{
    switch (code) {
    case HAL_DL_OK: return "ok";
    case HAL_DL_ENOLIB: return "shared library not installed";
    case HAL_DL_ENOSYM: return "shared library lacks a function (another version)";
    case HAL_DL_EARG: return "no such library in this build";
    default: return "unknown library loading error";
    }
}

static int resolve(hal_dl_t *l)
{
    void *syms[HAL_DL_MAXSYM];
    const char *what = l->what ? l->what : "this command";
    if (!l->soname || !*l->soname || !l->fill || l->count > HAL_DL_MAXSYM) {
        snprintf(l->err, sizeof l->err, "%s: %s", what, hal_dl_strerror(HAL_DL_EARG));
        return HAL_DL_EARG;
    }
    /* RTLD_LOCAL: its symbols serve this table only, nothing else binds to them. */
    void *h = dlopen(l->soname, RTLD_NOW | RTLD_LOCAL);
    if (!h) {
        const char *e = dlerror();
        snprintf(l->err, sizeof l->err, "%s needs %s: install the Debian package %s (%s)", what,
                 l->soname, l->package ? l->package : "that holds it", e ? e : "dlopen failed");
        return HAL_DL_ENOLIB;
    }
    for (size_t i = 0; i < l->count; i++) {
        dlerror();
        syms[i] = dlsym(h, l->names[i]);
        if (!syms[i]) {
            snprintf(l->err, sizeof l->err,
                     "%s needs %s from %s, which lacks it: install the version of the Debian "
                     "package %s this cellfit was built against",
                     what, l->names[i], l->soname, l->package ? l->package : "that holds it");
            dlclose(h);
            return HAL_DL_ENOSYM;
        }
    }
    l->fill(syms);
    l->handle = h; /* never closed: the table stays valid for the process */
    return HAL_DL_OK;
}

int hal_dl_load(hal_dl_t *l)
{
    int s = atomic_load_explicit(&l->state, memory_order_acquire);
    if (s)
        return s - 1;
    pthread_mutex_lock(&l->mu);
    s = atomic_load_explicit(&l->state, memory_order_relaxed);
    if (!s) {
        s = resolve(l) + 1;
        /* release: a thread that sees the state sees the table filled */
        atomic_store_explicit(&l->state, s, memory_order_release);
    }
    pthread_mutex_unlock(&l->mu);
    return s - 1;
}

const char *hal_dl_error(hal_dl_t *l)
{
    int s = atomic_load_explicit(&l->state, memory_order_acquire);
    return s > 1 ? l->err : "";
}
