/* fileio.c - whole-file reads, atomic writes and locale-independent numbers.
 *
 * Writes follow ecosystem-notes.md "Writing outputs": a mkstemp file beside
 * the target, every error checked, fsync, rename over the target, fsync of
 * the folder; any failure unlinks the temporary so no partial file survives
 * and the target keeps its old content.
 *
 * Numbers: one setlocale() anywhere in the process (a Lua recipe's
 * os.setlocale, a host application) changes strtod and printf's decimal
 * separator, so both go through a private "C" locale object. */
#include "core.h"

#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <locale.h>
#include <math.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

/* {====== reading */

femlod_status fl_file_read_all(const char *path, char **data, size_t *size, femlod_error *err) {
    int fd;
    do {
        fd = open(path, O_RDONLY | O_CLOEXEC);
    } while (fd < 0 && errno == EINTR);
    if (fd < 0) return fl_error(err, FEMLOD_EIO, "%s: cannot open: %s", path, strerror(errno));

    struct stat st;
    if (fstat(fd, &st) != 0) {
        int e = errno;
        close(fd);
        return fl_error(err, FEMLOD_EIO, "%s: cannot read: %s", path, strerror(e));
    }
    if (S_ISDIR(st.st_mode)) {
        close(fd);
        return fl_error(err, FEMLOD_EIO, "%s: cannot read: %s", path, strerror(EISDIR));
    }

    /* st_size is only a hint (pipes say 0, files may change under us): read to EOF. */
    size_t cap = 1 << 16;
    if (S_ISREG(st.st_mode) && st.st_size > 0) {
        if ((uintmax_t)st.st_size >= SIZE_MAX - 1) {
            close(fd);
            return fl_error(err, FEMLOD_ENOMEM, "%s: file too large for memory", path);
        }
        cap = (size_t)st.st_size + 1; /* + 1 sees EOF without growing */
    }
    char *buf = malloc(cap + 1);
    if (!buf) {
        close(fd);
        return fl_error(err, FEMLOD_ENOMEM, "%s: out of memory reading %zu bytes", path, cap);
    }
    size_t n = 0;
    for (;;) {
        if (n == cap) {
            size_t ncap;
            if (__builtin_mul_overflow(cap, (size_t)2, &ncap) || ncap == SIZE_MAX) {
                free(buf);
                close(fd);
                return fl_error(err, FEMLOD_ENOMEM, "%s: file too large for memory", path);
            }
            char *nb = realloc(buf, ncap + 1);
            if (!nb) {
                free(buf);
                close(fd);
                return fl_error(err, FEMLOD_ENOMEM, "%s: out of memory reading %zu bytes", path,
                                ncap);
            }
            buf = nb;
            cap = ncap;
        }
        ssize_t r = read(fd, buf + n, cap - n);
        if (r < 0) {
            if (errno == EINTR) continue;
            int e = errno;
            free(buf);
            close(fd);
            return fl_error(err, FEMLOD_EIO, "%s: cannot read: %s", path, strerror(e));
        }
        if (r == 0) break;
        n += (size_t)r;
    }
    close(fd);
    buf[n] = '\0';
    *data = buf;
    *size = n;
    return FEMLOD_OK;
}

/* }====== */

/* {====== atomic output */

/* The permissions a plain fopen() would have given a new file: mkstemp makes
 * 0600, which would hide results from other users. /proc avoids umask()'s
 * set-and-restore race with other threads; the fallback has that race. */
static mode_t default_mode(void) {
    mode_t mask = 022;
    int found = 0;
    FILE *f = fopen("/proc/self/status", "r");
    if (f) {
        char line[128];
        while (fgets(line, sizeof line, f)) {
            if (strncmp(line, "Umask:", 6) == 0) {
                char *e;
                unsigned long v = strtoul(line + 6, &e, 8);
                if (e != line + 6) {
                    mask = (mode_t)(v & 0777);
                    found = 1;
                }
                break;
            }
        }
        fclose(f);
    }
    if (!found) {
        mask = umask(022);
        umask(mask);
    }
    return (mode_t)(0666 & ~mask);
}

femlod_status fl_out_open(fl_out *o, const char *path, femlod_error *err) {
    static const char suffix[] = ".tmp.XXXXXX";
    o->fp = NULL;
    o->tmp_path = NULL;
    o->path = path;
    o->target = NULL;

    /* A symbolic link is followed: the file it points to is replaced and the
     * link stays, as a user who writes "through" a link expects. */
    struct stat lst;
    char *target;
    if (lstat(path, &lst) == 0 && S_ISLNK(lst.st_mode)) {
        target = realpath(path, NULL);
        if (!target)
            return fl_error(err, FEMLOD_EIO, "%s: cannot follow symbolic link: %s", path,
                            strerror(errno));
    } else {
        size_t n = strlen(path) + 1;
        target = fl_alloc(n, 1);
        if (!target) return fl_error(err, FEMLOD_ENOMEM, "%s: out of memory", path);
        memcpy(target, path, n);
    }

    /* Refused before anything is made: a folder (rename would fail only
     * after the whole file was written), and a file without any write
     * permission bit, which its owner meant to keep (root's rename would
     * replace it: the bits are checked, not access(), which root passes). */
    struct stat old;
    if (stat(target, &old) == 0) {
        const char *why = NULL;
        char buf[48];
        if (S_ISDIR(old.st_mode)) {
            why = strerror(EISDIR);
        } else if (S_ISREG(old.st_mode) && (old.st_mode & 0222) == 0) {
            snprintf(buf, sizeof buf, "file is read-only (mode %04o)",
                     (unsigned)(old.st_mode & 07777));
            why = buf;
        }
        if (why) {
            free(target);
            return fl_error(err, FEMLOD_EIO, "%s: cannot write: %s", path, why);
        }
    }

    size_t len = strlen(target);
    char *tmp = fl_alloc(len + sizeof suffix, 1);
    if (!tmp) {
        free(target);
        return fl_error(err, FEMLOD_ENOMEM, "%s: out of memory", path);
    }
    memcpy(tmp, target, len);
    memcpy(tmp + len, suffix, sizeof suffix);

    int fd = mkstemp(tmp);
    if (fd < 0) {
        int e = errno;
        free(tmp);
        free(target);
        return fl_error(err, FEMLOD_EIO, "%s: cannot create temporary file: %s", path, strerror(e));
    }
    /* Replacing a file keeps its permissions; a new file gets the usual ones. */
    struct stat st;
    mode_t mode = (stat(target, &st) == 0 && S_ISREG(st.st_mode)) ? (mode_t)(st.st_mode & 07777)
                                                                : default_mode();
    if (fchmod(fd, mode) != 0) {
        int e = errno;
        close(fd);
        unlink(tmp);
        free(tmp);
        free(target);
        return fl_error(err, FEMLOD_EIO, "%s: cannot set permissions of temporary file: %s", path,
                        strerror(e));
    }
    FILE *fp = fdopen(fd, "wb");
    if (!fp) {
        int e = errno;
        close(fd);
        unlink(tmp);
        free(tmp);
        free(target);
        return fl_error(err, FEMLOD_EIO, "%s: cannot open temporary file: %s", path, strerror(e));
    }
    o->fp = fp;
    o->tmp_path = tmp;
    o->target = target;
    return FEMLOD_OK;
}

void fl_out_abort(fl_out *o) {
    if (o->fp) fclose(o->fp);
    if (o->tmp_path) {
        unlink(o->tmp_path);
        free(o->tmp_path);
    }
    free(o->target);
    o->fp = NULL;
    o->tmp_path = NULL;
    o->target = NULL;
}

/* The errno of a write that failed earlier, which the writer only left in
 * ferror: one more byte at the end of the temporary fails the same way (a
 * full disk, EFBIG past RLIMIT_FSIZE). EIO when it does not. */
static int write_errno(FILE *fp) {
    int fd = fileno(fp);
    struct stat st;
    if (fd < 0 || fstat(fd, &st) != 0) return EIO;
    ssize_t r;
    do {
        r = pwrite(fd, "", 1, st.st_size);
    } while (r < 0 && errno == EINTR);
    return r < 0 ? errno : EIO;
}

/* The rename is only durable once the folder entry is on disk too. */
static int sync_parent_dir(const char *path) {
    const char *slash = strrchr(path, '/');
    char *dir;
    if (!slash) {
        dir = fl_alloc(2, 1);
        if (!dir) return ENOMEM;
        memcpy(dir, ".", 2);
    } else {
        size_t n = slash == path ? 1 : (size_t)(slash - path);
        dir = fl_alloc(n + 1, 1);
        if (!dir) return ENOMEM;
        memcpy(dir, path, n);
        dir[n] = '\0';
    }
    int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    free(dir);
    if (fd < 0) return errno;
    int rc = 0;
    if (fsync(fd) != 0 && errno != EINVAL && errno != ENOTSUP && errno != EROFS) rc = errno;
    close(fd);
    return rc;
}

femlod_status fl_out_commit(fl_out *o, femlod_error *err) {
    const char *what = NULL;
    int e = 0;
    FILE *fp = o->fp;
    o->fp = NULL;
    if (!fp || !o->tmp_path) {
        what = "cannot write";
        e = EBADF;
    } else if (ferror(fp)) {
        /* A failed fwrite/fprintf earlier; errno may be long gone. */
        what = "cannot write";
        e = write_errno(fp);
        fclose(fp);
    } else if (fflush(fp) != 0) {
        what = "cannot write";
        e = errno;
        fclose(fp);
    } else if (fsync(fileno(fp)) != 0 && errno != EINVAL && errno != EROFS) {
        what = "cannot sync";
        e = errno;
        fclose(fp);
    } else if (fclose(fp) != 0) {
        what = "cannot close";
        e = errno;
    } else if (rename(o->tmp_path, o->target) != 0) {
        what = "cannot rename temporary file into place";
        e = errno;
    }
    if (what) {
        if (o->tmp_path) unlink(o->tmp_path);
        free(o->tmp_path);
        o->tmp_path = NULL;
        free(o->target);
        o->target = NULL;
        return fl_error(err, FEMLOD_EIO, "%s: %s: %s", o->path, what, strerror(e));
    }
    free(o->tmp_path);
    o->tmp_path = NULL;
    e = sync_parent_dir(o->target);
    free(o->target);
    o->target = NULL;
    if (e) {
        /* The new content is in place; only its durability is in doubt. */
        return fl_error(err, FEMLOD_EIO, "%s: written, but cannot sync its folder: %s", o->path,
                        strerror(e));
    }
    return FEMLOD_OK;
}

/* }====== */

/* {====== locale-independent numbers */

/* The "C" locale object, made once. Threads racing here each make one and
 * all but the first free theirs. */
static _Atomic(locale_t) c_locale_obj;

static locale_t c_locale(void) {
    locale_t loc = atomic_load_explicit(&c_locale_obj, memory_order_acquire);
    if (loc) return loc;
    locale_t made = newlocale(LC_NUMERIC_MASK, "C", (locale_t)0);
    if (!made) return (locale_t)0;
    locale_t expected = (locale_t)0;
    if (!atomic_compare_exchange_strong_explicit(&c_locale_obj, &expected, made,
                                                 memory_order_acq_rel, memory_order_acquire)) {
        freelocale(made);
        return expected;
    }
    return made;
}

/* strtod with the thread switched to the "C" locale (uselocale is per thread). */
static double strtod_c(const char *s, char **end) {
    locale_t loc = c_locale();
    if (!loc) return strtod(s, end); /* only when newlocale cannot make "C": never on glibc */
    locale_t old = uselocale(loc);
    double r = strtod(s, end);
    uselocale(old);
    return r;
}

static int lower(int c) { return (c >= 'A' && c <= 'Z') ? c + ('a' - 'A') : c; }

/* Case-insensitive prefix match of a word; returns its length or 0. */
static size_t match_word(const char *s, const char *word) {
    size_t i = 0;
    for (; word[i]; i++)
        if (lower((unsigned char)s[i]) != word[i]) return 0;
    return i;
}

/* Powers of ten that doubles hold exactly. */
static const double exact_pow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                     1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                     1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

double fl_strtod(const char *s, char **end) {
    const char *p = s;
    while (*p == ' ' || (*p >= '\t' && *p <= '\r')) p++; /* as strtod does */
    int neg = 0;
    if (*p == '+' || *p == '-') {
        neg = *p == '-';
        p++;
    }

    /* inf, infinity, nan, nan(chars): as strtod, so callers can name them. */
    size_t w;
    if ((w = match_word(p, "infinity")) || (w = match_word(p, "inf"))) {
        *end = (char *)(uintptr_t)(p + w);
        return neg ? -HUGE_VAL : HUGE_VAL;
    }
    if ((w = match_word(p, "nan"))) {
        const char *q = p + w;
        if (*q == '(') {
            const char *r = q + 1;
            while ((*r >= '0' && *r <= '9') ||
                   (lower((unsigned char)*r) >= 'a' && lower((unsigned char)*r) <= 'z') ||
                   *r == '_')
                r++;
            if (*r == ')') q = r + 1;
        }
        *end = (char *)(uintptr_t)q;
        return neg ? -NAN : NAN;
    }

    /* Decimal form only: "0x1p3" stops after the "0", as hex floats are not
     * accepted in mesh files (ecosystem-notes.md 5.2). */
    uint64_t m = 0;
    int nd = 0;        /* significant digits held in m */
    int truncated = 0; /* nonzero digits beyond the 19 that m holds */
    long exp10 = 0;
    int any = 0;
    while (*p >= '0' && *p <= '9') {
        any = 1;
        if (nd < 19) {
            if (m || *p != '0') {
                m = m * 10 + (uint64_t)(*p - '0');
                nd++;
            }
        } else {
            exp10++;
            if (*p != '0') truncated = 1;
        }
        p++;
    }
    if (*p == '.') {
        const char *q = p + 1;
        int frac = 0;
        while (*q >= '0' && *q <= '9') {
            frac = 1;
            if (nd < 19) {
                if (m || *q != '0') {
                    m = m * 10 + (uint64_t)(*q - '0');
                    nd++;
                }
                exp10--;
            } else if (*q != '0') {
                truncated = 1;
            }
            q++;
        }
        if (any || frac) {
            any = 1;
            p = q;
        }
    }
    if (!any) {
        *end = (char *)(uintptr_t)s;
        return 0.0;
    }
    if (*p == 'e' || *p == 'E') {
        const char *q = p + 1;
        int eneg = 0;
        if (*q == '+' || *q == '-') {
            eneg = *q == '-';
            q++;
        }
        if (*q >= '0' && *q <= '9') {
            long e = 0;
            while (*q >= '0' && *q <= '9') {
                if (e < 100000) e = e * 10 + (*q - '0'); /* saturates far past any double */
                q++;
            }
            exp10 += eneg ? -e : e;
            p = q;
        }
    }
    *end = (char *)(uintptr_t)p;

    /* Clinger's fast path: an exact integer below 2^53 times or over an exact
     * power of ten is one correctly rounded IEEE operation. Without
     * FLT_EVAL_METHOD 0 (x87) double rounding would break that. */
#if FLT_EVAL_METHOD == 0
    if (m == 0 && !truncated) return neg ? -0.0 : 0.0;
    if (!truncated && m <= (UINT64_C(1) << 53)) {
        double r = -1.0;
        if (exp10 >= 0 && exp10 <= 22) {
            r = (double)m * exact_pow10[exp10];
        } else if (exp10 < 0 && exp10 >= -22) {
            r = (double)m / exact_pow10[-exp10];
        } else if (exp10 > 22 && exp10 <= 22 + 15) {
            /* "1e30": move the excess into m while it stays exact. */
            uint64_t mm = m;
            long k = exp10 - 22;
            for (; k > 0 && mm <= (UINT64_C(1) << 53) / 10; k--) mm *= 10;
            if (k == 0) r = (double)mm * 1e22;
        }
        if (r >= 0.0) return neg ? -r : r;
    }
#else
    (void)exact_pow10;
    (void)truncated;
#endif
    char *e2;
    double r = strtod_c(s, &e2);
    return r;
}

/* The significand digits of an "%.Ne" string without trailing zeros, and
 * its exponent. */
static int e_form_parse(const char *s, char *digits, int *exponent) {
    int n = 0;
    const char *p = s;
    for (; *p && *p != 'e'; p++)
        if (*p >= '0' && *p <= '9') digits[n++] = *p;
    while (n > 1 && digits[n - 1] == '0') n--;
    *exponent = *p == 'e' ? atoi(p + 1) : 0;
    return n;
}

static int same_double(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }

int fl_format_double(char *buf, size_t size, double x) {
    char tmp[40];
    int n = 0;
    if (!isfinite(x)) {
        n = snprintf(tmp, sizeof tmp, "%s", isnan(x) ? "nan" : (x < 0 ? "-inf" : "inf"));
    } else {
        /* 17 significant digits always read back exactly; fewer often do.
         * When 15 do, so does every precision down to the shortest (for
         * normal numbers the 15-digit grid is coarser than a double's ulp),
         * so its digit count, trailing zeros dropped, is the shortest.
         * Subnormals have fewer bits than that: search them upwards. */
        char e_form[40];
        locale_t loc = c_locale();
        locale_t old = loc ? uselocale(loc) : (locale_t)0;
        int p = fabs(x) < DBL_MIN && x != 0.0 ? 1 : 15;
        for (; p < 17; p++) {
            char *e;
            snprintf(e_form, sizeof e_form, "%.*e", p - 1, x);
            if (same_double(fl_strtod(e_form, &e), x)) break;
        }
        if (p == 17) snprintf(e_form, sizeof e_form, "%.16e", x);
        if (loc) uselocale(old);

        /* Lay the verified digits out as "%.Pg" would (trailing zeros
         * dropped), so no second printf and no second parse is needed. */
        char d[24];
        int exponent;
        int k = e_form_parse(e_form, d, &exponent);
        /* %g switches to exponent form once the exponent reaches the
         * precision P = k: widen P so that integers such as 100 print as
         * "100", not "1e+02" (up to 15 digits, where a wider rounding still
         * gives the same decimal). */
        int prec = k;
        if (exponent >= k && exponent < 15) prec = exponent + 1;
        if (signbit(x)) tmp[n++] = '-';
        if (exponent < -4 || exponent >= prec) {
            tmp[n++] = d[0];
            if (k > 1) {
                tmp[n++] = '.';
                memcpy(tmp + n, d + 1, (size_t)k - 1);
                n += k - 1;
            }
            n += snprintf(tmp + n, sizeof tmp - (size_t)n, "e%c%02d", exponent < 0 ? '-' : '+',
                          exponent < 0 ? -exponent : exponent);
        } else if (exponent >= 0) {
            for (int i = 0; i <= exponent; i++) tmp[n++] = i < k ? d[i] : '0';
            if (k > exponent + 1) {
                tmp[n++] = '.';
                memcpy(tmp + n, d + exponent + 1, (size_t)(k - exponent - 1));
                n += k - exponent - 1;
            }
        } else {
            tmp[n++] = '0';
            tmp[n++] = '.';
            for (int i = 0; i < -exponent - 1; i++) tmp[n++] = '0';
            memcpy(tmp + n, d, (size_t)k);
            n += k;
        }
        tmp[n] = '\0';
    }
    if (n < 0 || (size_t)n >= size) {
        if (size) buf[0] = '\0';
        return -1;
    }
    memcpy(buf, tmp, (size_t)n + 1);
    return n;
}

int fl_format_double_fit(char *buf, size_t size, double x, int width) {
    int n = fl_format_double(buf, size, x);
    if (n < 0 || n <= width) return n;
    /* too long: the most digits in exponent form that fit (the last digit
     * rounded) */
    char tmp[40];
    locale_t loc = c_locale();
    locale_t old = loc ? uselocale(loc) : (locale_t)0;
    int m = -1;
    for (int p = 16; p >= 0; p--) {
        m = snprintf(tmp, sizeof tmp, "%.*e", p, x);
        if (m > 0 && m <= width) break;
    }
    if (loc) uselocale(old);
    if (m < 0 || m > width || (size_t)m >= size) {
        if (size) buf[0] = '\0';
        return -1;
    }
    memcpy(buf, tmp, (size_t)m + 1);
    return m;
}

/* }====== */
