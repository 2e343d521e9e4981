/* SPDX-License-Identifier: MIT */
/* hal_dl.h: libraries loaded at their first use (issue 20), so that a
 * command that needs none of them (`cellfit --version`, a fit) maps none:
 * Aravis, libpq, libmosquitto, SQLite and libusb cost 2/3 of cellfit's
 * start-up when linked. A module lists the functions it calls in an
 * X-macro; HAL_DL_TABLE makes a table of typed pointers (`__typeof__(fn)
 * *`) from it and HAL_DL_LIB the library's record; hal_dl_load resolves
 * every symbol at once the first time (threads may race: one loads, the
 * others wait) and is sticky, success or failure. The soname and the
 * Debian package come from the build (mk/dl.mk): a missing library is an
 * error that says what to install.
 *
 *   #define SQL_SYMS(X) X(sqlite3_open_v2) X(sqlite3_close)
 *   HAL_DL_TABLE(sql, SQL_SYMS)
 *   static hal_dl_t sql_lib = HAL_DL_LIB(sql, HAL_DL_SONAME_SQLITE3,
 *                                        HAL_DL_PACKAGE_SQLITE3, "the results database");
 *   if (hal_dl_load(&sql_lib)) puts(hal_dl_error(&sql_lib));
 *   else sql.sqlite3_open_v2(...);
 *
 * hal/ is the lowest layer that both the rig (hal_gev, hal_usb) and the
 * cell (cf_resdb, cf_forward) may include, hence here and not in lib/. */
#ifndef HAL_DL_H
#define HAL_DL_H
#include <pthread.h>
#include <stdatomic.h>
#include <stddef.h>

/* hal_dl_load's results (hal_dl_strerror). */
enum {
    HAL_DL_OK = 0,
    HAL_DL_ENOLIB = 1, /* the library cannot be loaded (not installed) */
    HAL_DL_ENOSYM = 2, /* loaded, but a function is missing (another version) */
    HAL_DL_EARG = 3    /* no soname (a build without it) or too many symbols */
};

#define HAL_DL_MAXSYM 96 /* symbols a library's table may hold */

typedef struct hal_dl {
    const char *soname;  /* e.g. "libsqlite3.so.0", from the build */
    const char *package; /* the Debian package holding it, e.g. "libsqlite3-0" */
    const char *what;    /* who needs it, for the error: "the results database" */
    const char *const *names;
    size_t count;
    void (*fill)(void *const *syms); /* stores dlsym's results in the typed table */
    /* Set by the first hal_dl_load, under mu; state is read without it. */
    pthread_mutex_t mu;
    atomic_int state; /* 0 not yet tried, else the result + 1 */
    void *handle;
    char err[384];
} hal_dl_t;

/* Load l's library and resolve its table, the first time; HAL_DL_OK or the
 * first call's error again (hal_dl_error has the text). Thread-safe. */
int hal_dl_load(hal_dl_t *l);
/* The error of the last load: names the soname, the package to install and
 * what needed it; "" after success or before any load. */
const char *hal_dl_error(hal_dl_t *l);
const char *hal_dl_strerror(int code);

/* The table's parts, from an X-macro list of function names. The fill
 * casts dlsym's void * to each function's own pointer type (POSIX). */
#define HAL_DL_MEMBER_(f) __typeof__(f) *f;
#define HAL_DL_NAME_(f) #f,
#define HAL_DL_FILL_(f) t->f = (__typeof__(t->f))*p++;
#define HAL_DL_TABLE(tab, SYMS)                                                                    \
    static struct tab##_table {                                                                    \
        SYMS(HAL_DL_MEMBER_)                                                                       \
    } tab;                                                                                         \
    static const char *const tab##_names[] = {SYMS(HAL_DL_NAME_)};                                 \
    static void tab##_fill(void *const *p)                                                         \
    {                                                                                              \
        struct tab##_table *t = &tab;                                                              \
        SYMS(HAL_DL_FILL_)                                                                         \
    }
#define HAL_DL_LIB(tab, soname, package, what)                                                     \
    {                                                                                              \
        (soname), (package), (what), tab##_names, sizeof tab##_names / sizeof *tab##_names,        \
            tab##_fill, PTHREAD_MUTEX_INITIALIZER, 0, NULL,                                        \
        {                                                                                          \
            0                                                                                      \
        }                                                                                          \
    }
#endif
