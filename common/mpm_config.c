/* Case-file configuration: entries read from case files and the command line, checked
 * against a schema of key specs (see mpm_config.h).
 *
 * Invariants:
 *  - An entry's key is dotted (letters, digits, '_', '-'; '.' between non-empty components)
 *    and has at least one dot. Its value has no line break, no surrounding blanks and no
 *    comment, so "key = value" read back gives the same value (resolved_text relies on it).
 *  - Keys are unique. Entries keep the order in which keys first appeared, which is the
 *    instance order; a later source replaces a value in place.
 *  - Strings handed out (getters, where, instances) live as long as cfg: a replaced string
 *    is retired, not freed.
 *  - Every rank holds the same entries; messages go through mpm_log (rank 0 only).
 *  - The command line is one source, like one file: a key given twice there is an error.
 * Entries and specs are searched linearly: case files hold tens to hundreds of keys, and a
 * text with more than MAX_ENTRIES keys is refused (it is no case file, and the linear
 * searches would make it slow). A case file must be a regular file of at most
 * MAX_CASE_BYTES; error lines are capped at MAX_ERROR_LINES per read or validation, with
 * one closing line counting the rest, so garbage gives a screenful, not a line per line.
 *
 * Resolved text (mpm_config_resolved_text) writes the keys that were set as "key = value"
 * lines and the defaults as commented lines: reading it back sets exactly what was set, so
 * every consumer sees the same configuration (a default written as a value would count as
 * set: an obstacle's angle_of_attack would then be refused for a circle). Each line's
 * comment names where its value came from; reading a resolved text back keeps those names,
 * so resolving it again gives the same text.
 *
 * libinih splits lines into sections and name = value pairs. Our reader feeds it one line
 * at a time, so it knows the line number when the handler runs, and it checks each line
 * first: inih reports only the first bad line and not why, and truncates section names
 * longer than 49 bytes, so the reader reports syntax errors itself, hands inih a blank line
 * instead, and keeps the full section name. */
#define _POSIX_C_SOURCE 200809L

#include "mpm_config.h"
#include "mpm_error.h"

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <ini.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

typedef struct {
  char *key, *value;
  char *path;  /* value resolved against its file's folder (what a PATH key means) */
  char *where; /* "case.ini:12" or "command line" */
  char *from;  /* provenance carried over from a resolved text, or NULL */
  int line;    /* 0 for the command line */
  int source;  /* read call that set it: a key twice in one file is an error */
} entry;

typedef struct {
  char *prefix;
  char **names;
  int count;
} name_list;

struct mpm_config {
  MPI_Comm comm;
  const mpm_key_spec **specs;
  size_t nspecs, cap_specs;
  entry *entries;
  size_t n, cap;
  char **retired; /* replaced strings, still pointed to by earlier getter results */
  size_t nretired, cap_retired;
  name_list *lists; /* instances() results, cached because cfg owns them */
  size_t nlists, cap_lists;
  int nsources;
  int cmdline_source; /* source number of the command line, 0 before the first override */
  /* Error lines shown and held back since the last flush, the origin of the first one held
   * back ("case.ini", "command line"), and whether later ones came from elsewhere. */
  int err_shown;
  long long err_hidden;
  char err_origin[256];
  int err_mixed;
};

enum {
  MAX_ERROR_LINES = 20,             /* error lines printed before the rest are only counted */
  MAX_ENTRIES = 10000,              /* keys a text may set: case files hold hundreds at most */
  MAX_CASE_BYTES = 16 * 1024 * 1024 /* size of a case file */
};

/* The first line of a resolved text; reading a text that starts with it keeps provenance. */
static const char g_resolved_header[] = "# Resolved configuration:";

/* ---- growable arrays and strings ----------------------------------------------------- */

/* Make arr (cap items) hold at least need items, or fail the calling function. */
#define RESERVE(arr, need, cap)                                                                    \
  do {                                                                                             \
    if ((need) > (cap)) {                                                                          \
      size_t c_ = (cap) ? (cap) : 8;                                                               \
      while (c_ < (need)) c_ *= 2;                                                                 \
      void *p_ = realloc((arr), c_ * sizeof *(arr));                                               \
      if (!p_) MPM_FAIL(MPM_ERR_MEMORY, "out of memory while handling the configuration");         \
      (arr) = p_;                                                                                  \
      (cap) = c_;                                                                                  \
    }                                                                                              \
  } while (0)

/* Text built piece by piece; after a failed allocation it stays marked failed. */
typedef struct {
  char *s;
  size_t len, cap;
  int failed;
} sbuf;

static void sb_add(sbuf *b, const char *s, size_t n) {
  /* (No text is half the address space long; saying so spares -O3 a bound it cannot prove.) */
  if (b->failed || n > PTRDIFF_MAX / 2) {
    b->failed = 1;
    return;
  }
  if (b->len + n + 1 > b->cap) {
    size_t cap = b->cap ? b->cap : 64;
    while (cap < b->len + n + 1) cap *= 2;
    char *p = realloc(b->s, cap);
    if (!p) {
      b->failed = 1;
      return;
    }
    b->s = p;
    b->cap = cap;
  }
  memcpy(b->s + b->len, s, n);
  b->len += n;
  b->s[b->len] = '\0';
}

static void sb_str(sbuf *b, const char *s) {
  sb_add(b, s, strlen(s));
}

static void sb_vprintf(sbuf *b, const char *fmt, va_list ap) {
  va_list ap2;
  va_copy(ap2, ap);
  int n = vsnprintf(NULL, 0, fmt, ap2);
  va_end(ap2);
  char *tmp = n >= 0 ? malloc((size_t)n + 1) : NULL;
  if (!tmp) {
    b->failed = 1;
    return;
  }
  vsnprintf(tmp, (size_t)n + 1, fmt, ap);
  sb_add(b, tmp, (size_t)n);
  free(tmp);
}

__attribute__((format(printf, 2, 3))) static void sb_printf(sbuf *b, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  sb_vprintf(b, fmt, ap);
  va_end(ap);
}

/* The text (the caller frees it), or NULL if an allocation failed. */
static char *sb_take(sbuf *b) {
  if (!b->s) sb_add(b, "", 0);
  if (b->failed) free(b->s);
  char *s = b->failed ? NULL : b->s;
  *b = (sbuf){0};
  return s;
}

static char *dup_n(const char *s, size_t n) {
  char *p = malloc(n + 1);
  if (p) {
    memcpy(p, s, n);
    p[n] = '\0';
  }
  return p;
}

/* ---- text helpers -------------------------------------------------------------------- */

/* Messages quote user text shortened, with control bytes as '?', to stay on one line. */
enum { SHOW_MAX = 120 };
typedef struct {
  char s[SHOW_MAX + 4];
} shown;

static shown show_n(const char *s, size_t n) {
  shown out;
  size_t k = n > SHOW_MAX ? SHOW_MAX : n;
  for (size_t i = 0; i < k; ++i) {
    unsigned char c = (unsigned char)s[i];
    out.s[i] = (char)(c < 0x20 || c == 0x7f ? '?' : c);
  }
  strcpy(out.s + k, n > k ? "..." : "");
  return out;
}

static shown show(const char *s) {
  return show_n(s, strlen(s));
}

/* The blanks inih strips (isspace in the C locale, without the newline). */
static int is_blank(int c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

static void trim(const char **s, size_t *n) {
  while (*n && is_blank((unsigned char)**s)) ++*s, --*n;
  while (*n && is_blank((unsigned char)(*s)[*n - 1])) --*n;
}

/* Cut a comment: '#' or ';' at the start or after a blank or '='. A value can thus never
 * start with a comment character, which keeps "key = value" lines unambiguous. */
static void cut_comment(const char *s, size_t *n) {
  for (size_t i = 0; i < *n; ++i) {
    if (s[i] != '#' && s[i] != ';') continue;
    if (i == 0 || is_blank((unsigned char)s[i - 1]) || s[i - 1] == '=') {
      *n = i;
      return;
    }
  }
}

static int key_char(int c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
         c == '-';
}

/* 1 if s[0..n) is dotted: non-empty components of key characters; with wild, a component
 * may also be exactly "*". */
static int dotted_ok(const char *s, size_t n, int wild) {
  size_t start = 0;
  for (size_t i = 0; i <= n; ++i) {
    if (i < n && s[i] != '.') {
      if (!key_char((unsigned char)s[i]) && !(wild && s[i] == '*')) return 0;
      continue;
    }
    size_t len = i - start;
    if (len == 0 || (len > 1 && memchr(s + start, '*', len))) return 0;
    start = i + 1;
  }
  return 1;
}

/* Length of the section part of a dotted key (up to its last dot). */
static size_t section_len(const char *key) {
  const char *dot = strrchr(key, '.');
  return dot ? (size_t)(dot - key) : 0;
}

static int is_star(const char *p, size_t n) {
  return n == 1 && *p == '*';
}

/* 1 if key matches the spec pattern component by component, "*" matching any one. */
static int key_matches(const char *pat, const char *key) {
  for (;;) {
    size_t pl = strcspn(pat, "."), kl = strcspn(key, ".");
    if (!is_star(pat, pl) && (pl != kl || memcmp(pat, key, pl) != 0)) return 0;
    pat += pl, key += kl;
    if (!*pat || !*key) return !*pat && !*key;
    ++pat, ++key;
  }
}

/* If key lies in a section matching pat[0..n) (components, "*" = any) and goes on past it,
 * the length of that section's name in key; else 0. */
static size_t section_in(const char *key, const char *pat, size_t n) {
  const char *k = key, *p = pat, *end = pat + n;
  for (;;) {
    size_t pl = strcspn(p, "."), kl = strcspn(k, ".");
    if (pl > (size_t)(end - p)) pl = (size_t)(end - p);
    if (!is_star(p, pl) && (pl != kl || memcmp(p, k, pl) != 0)) return 0;
    p += pl, k += kl;
    if (*k != '.') return 0;
    if (p >= end) return (size_t)(k - key);
    ++p, ++k;
  }
}

/* ---- lookup and lifetime ------------------------------------------------------------- */

static const char *help_of(const mpm_key_spec *sp) {
  return sp->help ? sp->help : "";
}

/* " (help)" as three "%s" arguments, or nothing when there is no help text. */
#define PAREN(h) (*(h) ? " (" : ""), (h), (*(h) ? ")" : "")

/* The spec of key: an exact one first, else the first wildcard that matches. */
static const mpm_key_spec *find_spec(const mpm_config *cfg, const char *key) {
  const mpm_key_spec *wild = NULL;
  for (size_t i = 0; i < cfg->nspecs; ++i) {
    const mpm_key_spec *sp = cfg->specs[i];
    if (strcmp(sp->key, key) == 0) return sp;
    if (!wild && strchr(sp->key, '*') && key_matches(sp->key, key)) wild = sp;
  }
  return wild;
}

static entry *find_entry(const mpm_config *cfg, const char *key) {
  for (size_t i = 0; i < cfg->n; ++i)
    if (strcmp(cfg->entries[i].key, key) == 0) return &cfg->entries[i];
  return NULL;
}

/* ---- error lines --------------------------------------------------------------------- */

/* Length of the origin in a where text: "case.ini" of "case.ini:12". */
static size_t origin_len(const char *where) {
  const char *colon = strrchr(where, ':');
  if (colon && colon[1] && strspn(colon + 1, "0123456789") == strlen(colon + 1))
    return (size_t)(colon - where);
  return strlen(where);
}

/* 1 if one more error line may be printed; else the error is only counted, for
 * errors_flush to sum up. The count lives in cfg behind a const pointer, like the instance
 * cache (sound: cfg is never defined const). */
static int error_room(const mpm_config *cfg, const char *where) {
  mpm_config *c = (mpm_config *)cfg;
  if (c->err_shown < MAX_ERROR_LINES) {
    ++c->err_shown;
    return 1;
  }
  const char *w = where ? where : "";
  size_t n = origin_len(w);
  if (n >= sizeof c->err_origin) n = sizeof c->err_origin - 1;
  if (c->err_hidden++ == 0)
    memcpy(c->err_origin, w, n), c->err_origin[n] = '\0';
  else if (strlen(c->err_origin) != n || memcmp(c->err_origin, w, n) != 0)
    c->err_mixed = 1;
  return 0;
}

/* One closing line for the errors held back, then a fresh budget. */
static void errors_flush(const mpm_config *cfg) {
  mpm_config *c = (mpm_config *)cfg;
  if (c->err_hidden > 0) {
    const char *o = c->err_mixed ? "" : c->err_origin;
    const int cl = strcmp(o, "command line") == 0;
    mpm_log(MPM_LOG_ERROR, "... and %lld more error%s%s%s; fix the ones above first", c->err_hidden,
            c->err_hidden == 1 ? "" : "s",
            !*o  ? ""
            : cl ? " on the "
                 : " in ",
            show(o).s);
  }
  c->err_shown = 0, c->err_hidden = 0, c->err_mixed = 0, c->err_origin[0] = '\0';
}

int mpm_config_new(mpm_config **cfg, MPI_Comm comm) {
  MPM_ALLOC(*cfg, 1);
  (*cfg)->comm = comm;
  return 0;
}

static void free_names(name_list *l) {
  for (int k = 0; k < l->count; ++k) free(l->names[k]);
  free(l->names);
  free(l->prefix);
}

void mpm_config_destroy(mpm_config **cfg) {
  if (!cfg || !*cfg) return;
  mpm_config *c = *cfg;
  for (size_t i = 0; i < c->n; ++i) {
    entry *e = &c->entries[i];
    free(e->key), free(e->value), free(e->path), free(e->where), free(e->from);
  }
  errors_flush(c); /* a consumer's errors past the cap */
  for (size_t i = 0; i < c->nretired; ++i) free(c->retired[i]);
  for (size_t i = 0; i < c->nlists; ++i) free_names(&c->lists[i]);
  free(c->entries), free(c->retired), free(c->lists), free(c->specs), free(c);
  *cfg = NULL;
}

/* ---- checking one value -------------------------------------------------------------- */

/* A value being checked or read, with what a message needs to name it. */
typedef struct {
  const mpm_config *cfg;
  const mpm_key_spec *sp;
  const char *key, *value;
  const char *path;  /* resolved, for PATH keys */
  const char *where; /* where it was set, or for a default where its section is; or NULL */
  int line;          /* 0: command line or default (relative paths start at the cwd) */
  int is_default;    /* the value is the spec's default */
} item;

/* One line: "where: key = value: msg (help)". */
static void report(const item *it, const char *msg, int with_help) {
  const char *help = it->sp && with_help ? help_of(it->sp) : "";
  if (!error_room(it->cfg, it->where)) return;
  mpm_log(MPM_LOG_ERROR, "%s%s%s = %s%s: %s%s%s%s", it->where ? it->where : "",
          it->where ? ": " : "", show(it->key).s, show(it->value).s,
          it->is_default ? " (default)" : "", msg, PAREN(help));
}

__attribute__((format(printf, 2, 3))) static int bad(const item *it, const char *fmt, ...) {
  sbuf b = {0};
  va_list ap;
  va_start(ap, fmt);
  sb_vprintf(&b, fmt, ap);
  va_end(ap);
  report(it, b.failed ? fmt : b.s, 1);
  free(b.s);
  return MPM_ERR_INPUT;
}

/* Why a text is not a usable real number (parse_real). */
enum { REAL_SYNTAX = -1, REAL_NONFINITE = -2, REAL_TINY = -3 };

/* Strict number parsing: the whole text must be the number, and a normal double or zero. NaN,
 * the infinities and overflows (REAL_NONFINITE) are refused, and so are values too small to
 * hold at full precision (REAL_TINY): subnormal ones (1e-320), and non-zero texts that round
 * to zero (1e-400). No physical input is that small, and arithmetic on them loses its
 * precision and runs slowly, so 1e-320 kg/m^3 is a typo, not a density. */
static int parse_real(const char *s, size_t n, double *v) {
  char *end;
  if (n == 0 || is_blank((unsigned char)*s)) return REAL_SYNTAX;
  errno = 0;
  double x = strtod(s, &end);
  if (end != s + n) return REAL_SYNTAX;
  if (!isfinite(x) || (errno == ERANGE && fabs(x) == HUGE_VAL)) return REAL_NONFINITE;
  if (fpclassify(x) == FP_SUBNORMAL || (errno == ERANGE && x == 0)) return REAL_TINY;
  *v = x;
  return 0;
}

/* What to say about a text parse_real refused with code why. */
static const char *real_problem(int why) {
  if (why == REAL_NONFINITE)
    return "is not finite (NaN, an infinity, or beyond 1.8e308); give a finite real number";
  if (why == REAL_TINY)
    return "is smaller in magnitude than 2.2e-308 (subnormal, or it rounds to 0), too small "
           "to compute with; check its exponent";
  return "is not a real number";
}

/* 0, -1 if not an integer, -2 if out of the range of int. */
static int parse_int(const char *s, int *v) {
  char *end;
  if (!*s || is_blank((unsigned char)*s)) return -1;
  errno = 0;
  long x = strtol(s, &end, 10);
  if (*end) return -1;
  if (errno == ERANGE || x < INT_MIN || x > INT_MAX) return -2;
  *v = (int)x;
  return 0;
}

static int parse_bool(const char *s, int *v) {
  static const char *const words[] = {"false", "true", "no", "yes", "off", "on", "0", "1"};
  for (int i = 0; i < 8; ++i)
    if (strcasecmp(s, words[i]) == 0) {
      *v = i % 2;
      return 0;
    }
  return -1;
}

/* Next blank- or comma-separated item of s at or after *pos; 0 when there is none. */
static int next_item(const char *s, size_t *pos, const char **item_s, size_t *item_n) {
  size_t i = *pos;
  while (s[i] && (is_blank((unsigned char)s[i]) || s[i] == ',')) ++i;
  if (!s[i]) return 0;
  size_t j = i;
  while (s[j] && !is_blank((unsigned char)s[j]) && s[j] != ',') ++j;
  *item_s = s + i, *item_n = j - i, *pos = j;
  return 1;
}

/* Specs that leave min and max at 0 mean "no range" (a range of one point makes no sense). */
static int has_range(const mpm_key_spec *sp) {
  return !(sp->min == 0 && sp->max == 0 && !sp->min_exclusive);
}

static int in_range(const mpm_key_spec *sp, double x) {
  if (!has_range(sp)) return 1;
  if (sp->min_exclusive ? !(x > sp->min) : !(x >= sp->min)) return 0;
  return x <= sp->max;
}

/* "> 0", ">= 0", "<= 1", "in (0, 1]" ... */
static shown range_text(const mpm_key_spec *sp) {
  shown r;
  int lo = isfinite(sp->min), hi = isfinite(sp->max);
  if (lo && hi)
    snprintf(r.s, sizeof r.s, "in %c%.10g, %.10g]", sp->min_exclusive ? '(' : '[', sp->min,
             sp->max);
  else if (lo)
    snprintf(r.s, sizeof r.s, "%s %.10g", sp->min_exclusive ? ">" : ">=", sp->min);
  else if (hi)
    snprintf(r.s, sizeof r.s, "<= %.10g", sp->max);
  else
    snprintf(r.s, sizeof r.s, "finite");
  return r;
}

static int check_real(const item *it) {
  double x;
  const int why = parse_real(it->value, strlen(it->value), &x);
  if (why == REAL_SYNTAX) return bad(it, "expected a finite real number");
  if (why) return bad(it, "%s", real_problem(why));
  if (!in_range(it->sp, x)) return bad(it, "must be %s", range_text(it->sp).s);
  return 0;
}

static int check_int(const item *it) {
  int x = 0, rc = parse_int(it->value, &x);
  if (rc == -1) return bad(it, "expected a whole number");
  if (rc == -2) return bad(it, "too large for an integer");
  if (!in_range(it->sp, x)) return bad(it, "must be %s", range_text(it->sp).s);
  return 0;
}

static size_t edit_distance(const char *a, const char *b, size_t limit);

/* A wrong choice names the nearest one when it is a likely typo (a third of the word away at
 * most, at least 2). */
static int check_enum(const item *it) {
  const char *c = it->sp->choices ? it->sp->choices : "";
  size_t n = strlen(it->value), limit = n / 3 < 2 ? 2 : n / 3, best = limit + 1;
  char near[64] = "";
  for (;;) {
    size_t len = strcspn(c, "|");
    if (len == n && memcmp(c, it->value, n) == 0) return 0;
    if (len < sizeof near) {
      char cand[64];
      memcpy(cand, c, len), cand[len] = '\0';
      const size_t d = edit_distance(it->value, cand, limit);
      if (d < best) best = d, memcpy(near, cand, len + 1);
    }
    if (!c[len]) break;
    c += len + 1;
  }
  if (*near) return bad(it, "did you mean '%s'? Expected one of %s", near, it->sp->choices);
  return bad(it, "expected one of %s", it->sp->choices ? it->sp->choices : "(none)");
}

static int check_reals(const item *it) {
  const mpm_key_spec *sp = it->sp;
  size_t pos = 0, n;
  const char *s;
  int count = 0;
  double x;
  while (next_item(it->value, &pos, &s, &n)) {
    ++count;
    const int why = parse_real(s, n, &x);
    if (why == REAL_SYNTAX)
      return bad(it, "value %d ('%s') is not a finite real number", count, show_n(s, n).s);
    if (why) return bad(it, "value %d ('%s') %s", count, show_n(s, n).s, real_problem(why));
    if (!in_range(sp, x)) return bad(it, "value %d (%g) must be %s", count, x, range_text(sp).s);
  }
  if (count == 0) return bad(it, "expected one or more real numbers");
  if (sp->max_count > 0 && count > sp->max_count)
    return bad(it, "too many values: %d given, at most %d", count, sp->max_count);
  return 0;
}

static int check_names(const item *it) {
  size_t pos = 0, n;
  const char *s;
  if (!next_item(it->value, &pos, &s, &n)) return bad(it, "expected one or more names");
  return 0;
}

static int check_path(const item *it) {
  struct stat st;
  if (!*it->value) return bad(it, "expected the path of a file");
  const char *from = it->line > 0 ? "the case file's folder" : "the current folder";
  if (stat(it->path, &st) != 0)
    return bad(it, "cannot open '%s': %s; check the path (relative paths start at %s)", it->path,
               strerror(errno), from);
  if (S_ISDIR(st.st_mode)) return bad(it, "'%s' is a folder; give a file", it->path);
  /* A device or FIFO could be read forever: only regular files are data. */
  if (!S_ISREG(st.st_mode))
    return bad(it, "'%s' is not a regular file (a device, FIFO or socket); give a file", it->path);
  return 0;
}

/* 0 if the value fits its spec; else reports it and returns MPM_ERR_INPUT. */
static int check_value(const item *it) {
  int v;
  switch (it->sp->type) {
  case MPM_KEY_REAL:
    return check_real(it);
  case MPM_KEY_INT:
    return check_int(it);
  case MPM_KEY_BOOL:
    if (parse_bool(it->value, &v) == 0) return 0;
    return bad(it, "expected true or false (or yes/no, on/off, 1/0)");
  case MPM_KEY_STRING:
    return 0;
  case MPM_KEY_ENUM:
    return check_enum(it);
  case MPM_KEY_REALS:
    return check_reals(it);
  case MPM_KEY_NAMES:
    return check_names(it);
  case MPM_KEY_PATH:
    return check_path(it);
  }
  return bad(it, "internal error: unknown key type %d", (int)it->sp->type);
}

static item entry_item(const mpm_config *cfg, const mpm_key_spec *sp, const entry *e) {
  return (item){cfg, sp, e->key, e->value, e->path, e->where, e->line, 0};
}

/* ---- schema ------------------------------------------------------------------------ */

/* A spec table is program text: a bad one is an internal error, found when it is added. */
static int check_spec(const mpm_config *cfg, const mpm_key_spec *sp) {
  const char *k = sp->key;
  if (!k || !dotted_ok(k, strlen(k), 1) || !strchr(k, '.') || strcmp(strrchr(k, '.'), ".*") == 0)
    MPM_FAIL(MPM_ERR_INTERNAL, "schema key '%s' is not section.key ('*' only for an instance)",
             k ? show(k).s : "(null)");
  if ((unsigned)sp->type > MPM_KEY_PATH)
    MPM_FAIL(MPM_ERR_INTERNAL, "schema key '%s' has an unknown type", show(k).s);
  if (sp->type == MPM_KEY_ENUM && (!sp->choices || !*sp->choices))
    MPM_FAIL(MPM_ERR_INTERNAL, "schema key '%s' is an enum without choices", show(k).s);
  for (size_t i = 0; i < cfg->nspecs; ++i)
    if (strcmp(cfg->specs[i]->key, k) == 0)
      MPM_FAIL(MPM_ERR_INTERNAL, "schema key '%s' is declared twice", show(k).s);
  item it = {cfg, sp, k, sp->def, sp->def, NULL, 0, 1};
  if (sp->def && sp->type != MPM_KEY_PATH && check_value(&it) != 0)
    MPM_FAIL(MPM_ERR_INTERNAL, "schema key '%s' has a bad default", show(k).s);
  return 0;
}

int mpm_config_add_schema(mpm_config *cfg, const mpm_key_spec *specs, int n) {
  if (n < 0 || (n > 0 && !specs)) MPM_FAIL(MPM_ERR_INTERNAL, "bad schema table (n = %d)", n);
  RESERVE(cfg->specs, cfg->nspecs + (size_t)n, cfg->cap_specs);
  for (int i = 0; i < n; ++i) {
    MPM_CALL(check_spec(cfg, &specs[i]));
    cfg->specs[cfg->nspecs++] = &specs[i];
  }
  return 0;
}

const mpm_key_spec *mpm_config_spec(const mpm_config *cfg, size_t k) {
  return k < cfg->nspecs ? cfg->specs[k] : NULL;
}

const char *mpm_config_type_name(mpm_key_type type) {
  static const char *const name[] = {"real",   "int",   "bool",  "text",
                                     "choice", "reals", "names", "path"};
  return (unsigned)type < sizeof name / sizeof name[0] ? name[type] : "?";
}

void mpm_config_allowed_text(const mpm_key_spec *sp, char *buf, size_t n) {
  const int ranged =
      sp->type == MPM_KEY_REAL || sp->type == MPM_KEY_INT || sp->type == MPM_KEY_REALS;
  /* An unbounded real range reads "finite" in messages; here that says nothing. */
  const int bounded = has_range(sp) && (isfinite(sp->min) || isfinite(sp->max));
  shown r = {""};
  if (ranged && bounded) r = range_text(sp);
  const char *range = r.s;
  if (sp->type == MPM_KEY_ENUM)
    snprintf(buf, n, "%s", sp->choices ? sp->choices : "");
  else if (sp->type == MPM_KEY_REALS && sp->max_count > 0)
    snprintf(buf, n, "%s%sat most %d value%s", range, *range ? ", " : "", sp->max_count,
             sp->max_count > 1 ? "s" : "");
  else
    snprintf(buf, n, "%s", range);
}

/* ---- entries ------------------------------------------------------------------------- */

/* Where an entry comes from. */
typedef struct {
  const char *origin; /* file name or "command line" */
  const char *dir;    /* folder for relative paths; NULL for the current one */
  int line;           /* 0 for the command line */
  int source;
  const char *from; /* the line's provenance comment, in a resolved text; else NULL */
} place;

static char *resolve_path(const char *dir, const char *value) {
  if (!dir || !*dir || strcmp(dir, ".") == 0 || !*value || value[0] == '/') return strdup(value);
  sbuf b = {0};
  sb_str(&b, dir);
  if (dir[strlen(dir) - 1] != '/') sb_add(&b, "/", 1);
  sb_str(&b, value);
  return sb_take(&b);
}

static char *where_text(const place *at) {
  if (at->line <= 0) return strdup(at->origin);
  sbuf b = {0};
  sb_printf(&b, "%s:%d", at->origin, at->line);
  return sb_take(&b);
}

/* A key set twice by one source: a file names both lines, the command line both
 * assignments. */
static int duplicate(const mpm_config *cfg, const entry *e, const char *value, const place *at) {
  if (at->line > 0 && error_room(cfg, at->origin))
    mpm_log(MPM_LOG_ERROR, "%s:%d: %s is set twice (lines %d and %d); keep one", at->origin,
            at->line, show(e->key).s, e->line, at->line);
  else if (at->line <= 0 && error_room(cfg, at->origin))
    mpm_log(MPM_LOG_ERROR, "%s: %s is given twice (%s=%s and %s=%s); keep one", at->origin,
            show(e->key).s, show(e->key).s, show(e->value).s, show(e->key).s, show(value).s);
  return MPM_ERR_INPUT;
}

/* Replace e's value in place, keeping its position; the old strings are retired. */
static void replace(mpm_config *cfg, entry *e, entry *n) {
  cfg->retired[cfg->nretired++] = e->value;
  cfg->retired[cfg->nretired++] = e->path;
  cfg->retired[cfg->nretired++] = e->where;
  if (e->from) cfg->retired[cfg->nretired++] = e->from;
  e->value = n->value, e->path = n->path, e->where = n->where, e->from = n->from;
  e->line = n->line, e->source = n->source;
}

static int too_many_keys(const mpm_config *cfg, const place *at) {
  if (error_room(cfg, at->origin))
    mpm_log(MPM_LOG_ERROR,
            "%s:%d: more than %d keys; a case file holds tens to hundreds: is this a case "
            "file?",
            at->origin, at->line, MAX_ENTRIES);
  return MPM_ERR_INPUT;
}

static int set_entry(mpm_config *cfg, const char *key, const char *value, const place *at) {
  entry *e = find_entry(cfg, key);
  if (e && e->source == at->source) return duplicate(cfg, e, value, at);
  if (!e && cfg->n >= MAX_ENTRIES) return too_many_keys(cfg, at);
  if (e)
    RESERVE(cfg->retired, cfg->nretired + 4, cfg->cap_retired);
  else
    RESERVE(cfg->entries, cfg->n + 1, cfg->cap);
  entry n = {NULL,
             strdup(value),
             resolve_path(at->dir, value),
             where_text(at),
             at->from ? strdup(at->from) : NULL,
             at->line,
             at->source};
  if (!e) n.key = strdup(key);
  if (!n.value || !n.path || !n.where || (!e && !n.key) || (at->from && !n.from)) {
    free(n.key), free(n.value), free(n.path), free(n.where), free(n.from);
    MPM_FAIL(MPM_ERR_MEMORY, "out of memory storing '%s'", show(key).s);
  }
  if (e)
    replace(cfg, e, &n);
  else
    cfg->entries[cfg->n++] = n;
  return 0;
}

/* ---- reading case text ------------------------------------------------------------- */

typedef struct {
  mpm_config *cfg;
  place at;         /* at.line is the line last served to inih */
  const char *next; /* start of the next unread line */
  sbuf line;        /* cleaned line being served, with its '\n' */
  size_t served;    /* bytes of line already handed to inih */
  sbuf section;     /* current section name; empty before the first header */
  sbuf from;        /* a resolved text's provenance comment on the line, if any */
  int resolved;     /* the text is a resolved text (it starts with g_resolved_header) */
  int section_ok;   /* 0 after a bad header: its keys are skipped (already reported) */
  int stop;         /* 1: give up reading (too many keys) */
  int rc;           /* first failure */
} parser;

__attribute__((format(printf, 2, 3))) static int parse_error(parser *ps, const char *fmt, ...) {
  sbuf b = {0};
  va_list ap;
  va_start(ap, fmt);
  sb_vprintf(&b, fmt, ap);
  va_end(ap);
  if (error_room(ps->cfg, ps->at.origin))
    mpm_log(MPM_LOG_ERROR, "%s:%d: %s", ps->at.origin, ps->at.line, b.failed ? fmt : b.s);
  free(b.s);
  if (!ps->rc) ps->rc = MPM_ERR_INPUT;
  return 0;
}

static int lex_section(parser *ps, const char *s, size_t n) {
  const char *close = memchr(s, ']', n);
  ps->section_ok = 0;
  ps->section.len = 0;
  if (!close)
    return parse_error(ps, "syntax error: '[' without a closing ']' in '%s'", show_n(s, n).s);
  if (close != s + n - 1)
    return parse_error(ps, "syntax error: unexpected text after ']' in '%s'", show_n(s, n).s);
  const char *name = s + 1;
  size_t len = (size_t)(close - name);
  trim(&name, &len);
  if (!dotted_ok(name, len, 0))
    return parse_error(ps,
                       "syntax error: bad section name '[%s]': use letters, digits, '_' or "
                       "'-', with '.' between parts",
                       show_n(name, len).s);
  sb_add(&ps->section, name, len);
  ps->section_ok = 1;
  return 1;
}

/* 1 if the cleaned, non-empty line s[0..n) can go to inih; else reports it. */
static int lex_line(parser *ps, const char *s, size_t n) {
  if (s[0] == '[') return lex_section(ps, s, n);
  const char *eq = memchr(s, '=', n);
  if (!eq)
    return parse_error(ps, "syntax error: expected 'key = value' or '[section]', got '%s'",
                       show_n(s, n).s);
  size_t kn = (size_t)(eq - s);
  trim(&s, &kn);
  if (kn == 0) return parse_error(ps, "syntax error: no key before '='");
  if (!dotted_ok(s, kn, 0))
    return parse_error(ps,
                       "syntax error: bad key '%s': use letters, digits, '_' or '-', with '.' "
                       "between parts",
                       show_n(s, kn).s);
  if (!ps->section_ok) return 0;
  if (ps->section.len == 0)
    return parse_error(ps, "key '%s' is outside any section; put it under a [section] header",
                       show_n(s, kn).s);
  return 1;
}

/* In a resolved text, the comment after a value names where the value came from: keep it
 * (c[0..n) is the comment with its '#'), so that resolving the text again names the same. */
static void keep_provenance(parser *ps, const char *c, size_t n) {
  ps->from.len = 0;
  if (!ps->resolved || n < 2) return;
  ++c, --n;
  trim(&c, &n);
  if (n) sb_add(&ps->from, c, n);
}

/* Clean the next physical line (blanks, comment, a leading byte-order mark) into ps->line;
 * a bad line becomes blank. */
static void next_line(parser *ps) {
  const char *s = ps->next, *eol = strchr(s, '\n');
  size_t n = eol ? (size_t)(eol - s) : strlen(s);
  ps->next = s + n + (eol != NULL);
  ps->at.line++;
  ps->line.len = 0;
  ps->served = 0;
  if (ps->at.line == 1 && n >= 3 && memcmp(s, "\xEF\xBB\xBF", 3) == 0) s += 3, n -= 3;
  if (ps->at.line == 1)
    ps->resolved = strncmp(s, g_resolved_header, strlen(g_resolved_header)) == 0;
  trim(&s, &n);
  size_t whole = n;
  cut_comment(s, &n);
  keep_provenance(ps, s + n, whole - n);
  trim(&s, &n);
  if (n && !lex_line(ps, s, n)) n = 0;
  sb_add(&ps->line, s, n);
  sb_add(&ps->line, "\n", 1);
}

/* inih's fgets-like reader: one cleaned line per call (the buffer holds the longest). */
static char *read_line(char *str, int num, void *stream) {
  parser *ps = stream;
  if (ps->stop) return NULL;
  if (ps->served == ps->line.len) {
    if (!*ps->next) return NULL;
    next_line(ps);
  }
  if (ps->line.failed) {
    ps->rc = MPM_ERR_MEMORY;
    return NULL;
  }
  size_t n = ps->line.len - ps->served;
  if (num < 2 || n > (size_t)num - 1) {
    mpm_log(MPM_LOG_ERROR, "internal error: line %d does not fit inih's buffer", ps->at.line);
    ps->rc = MPM_ERR_INTERNAL;
    return NULL;
  }
  memcpy(str, ps->line.s + ps->served, n);
  str[n] = '\0';
  ps->served += n;
  return str;
}

/* inih's handler; inih's section argument may be truncated, so the reader's name is used. */
static int on_pair(void *user, const char *section, const char *name, const char *value) {
  parser *ps = user;
  sbuf key = {0};
  (void)section;
  sb_add(&key, ps->section.s, ps->section.len);
  sb_add(&key, ".", 1);
  sb_str(&key, name);
  if (ps->from.failed) key.failed = 1;
  ps->at.from = ps->from.len ? ps->from.s : NULL;
  int rc = key.failed ? MPM_ERR_MEMORY : set_entry(ps->cfg, key.s, value, &ps->at);
  if (rc && !ps->rc) ps->rc = rc;
  if (rc && ps->cfg->n >= MAX_ENTRIES) ps->stop = 1;
  free(key.s);
  return 1;
}

static size_t longest_line(const char *s) {
  size_t best = 0;
  while (*s) {
    size_t n = strcspn(s, "\n");
    if (n > best) best = n;
    s += n + (s[n] == '\n');
  }
  return best;
}

/* Debian's libinih exposes its build options as variables. For one parse we want a heap
 * line buffer that holds the longest line (the default is 200 bytes, and a longer line
 * would be split silently) and no multi-line values. Like all of reading, not thread-safe. */
typedef struct {
  bool use_stack, allow_realloc, allow_multiline, stop_on_first_error, allow_no_value;
  int max_line, initial_alloc;
} ini_options;

static ini_options ini_options_set(int line_bytes) {
  ini_options old = {ini_use_stack,           ini_allow_realloc,  ini_allow_multiline,
                     ini_stop_on_first_error, ini_allow_no_value, ini_max_line,
                     ini_initial_alloc};
  ini_use_stack = ini_allow_realloc = ini_allow_multiline = false;
  ini_stop_on_first_error = ini_allow_no_value = false;
  ini_max_line = ini_initial_alloc = line_bytes;
  return old;
}

static void ini_options_restore(const ini_options *o) {
  ini_use_stack = o->use_stack, ini_allow_realloc = o->allow_realloc;
  ini_allow_multiline = o->allow_multiline, ini_stop_on_first_error = o->stop_on_first_error;
  ini_allow_no_value = o->allow_no_value;
  ini_max_line = o->max_line, ini_initial_alloc = o->initial_alloc;
}

int mpm_config_read_string(mpm_config *cfg, const char *text, const char *origin, const char *dir) {
  if (!cfg || !text) MPM_FAIL(MPM_ERR_INTERNAL, "mpm_config_read_string: NULL argument");
  parser ps = {.cfg = cfg,
               .at = {origin ? origin : "(text)", dir, 0, ++cfg->nsources, NULL},
               .next = text,
               .section_ok = 1};
  size_t longest = longest_line(text);
  errors_flush(cfg);
  if (longest > (size_t)INT_MAX - 8) {
    mpm_log(MPM_LOG_ERROR, "%s: a line is longer than %d bytes; is this a case file?", ps.at.origin,
            INT_MAX - 8);
    return MPM_ERR_INPUT;
  }
  ini_options saved = ini_options_set((int)longest + 3);
  int r = ini_parse_stream(read_line, &ps, on_pair, &ps);
  ini_options_restore(&saved);
  free(ps.line.s);
  free(ps.section.s);
  free(ps.from.s);
  if (r == -2 && !ps.rc) ps.rc = MPM_ERR_MEMORY;
  if (r > 0 && !ps.rc) {
    mpm_log(MPM_LOG_ERROR, "%s:%d: syntax error", ps.at.origin, r);
    ps.rc = MPM_ERR_INPUT;
  }
  errors_flush(cfg);
  return ps.rc ? mpm_trace(__FILE__, __LINE__, __func__, ps.rc) : 0;
}

/* Why rank 0 could not read a case file: an errno value, or one of these. */
enum { NOT_REGULAR = -1, TOO_LARGE = -2 };

/* What kind of non-regular file mode is. */
static const char *file_kind(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

/* Rank 0's part of read_file: the whole file, or an errno value or NOT_REGULAR (*kind set)
 * or TOO_LARGE. A device or FIFO would be read forever, or block the open: it is opened
 * without blocking and refused by its type; at most MAX_CASE_BYTES are read. */
static int slurp(const char *path, char **text, size_t *len, const char **kind) {
  int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  struct stat st;
  if (fd < 0) return errno ? errno : EIO;
  if (fstat(fd, &st) != 0) {
    int err = errno ? errno : EIO;
    close(fd);
    return err;
  }
  if (!S_ISREG(st.st_mode)) {
    *kind = file_kind(st.st_mode);
    close(fd);
    return NOT_REGULAR;
  }
  if (st.st_size > MAX_CASE_BYTES) {
    close(fd);
    return TOO_LARGE;
  }
  FILE *f = fdopen(fd, "rb");
  if (!f) {
    int err = errno ? errno : EIO;
    close(fd);
    return err;
  }
  sbuf b = {0};
  char chunk[1 << 16];
  size_t got;
  while (b.len <= MAX_CASE_BYTES && (got = fread(chunk, 1, sizeof chunk, f)) > 0)
    sb_add(&b, chunk, got);
  int err = ferror(f) ? (errno ? errno : EIO) : b.len > MAX_CASE_BYTES ? TOO_LARGE : 0;
  fclose(f);
  *len = b.len;
  *text = sb_take(&b);
  if (!err && !*text) err = ENOMEM;
  if (err) free(*text), *text = NULL;
  return err;
}

static void cannot_read(const char *path, int why, const char *kind) {
  if (why == NOT_REGULAR)
    mpm_log(MPM_LOG_ERROR,
            "%s: cannot read it as a case file: it is %s; give the path of a case file",
            show(path).s, kind);
  else if (why == TOO_LARGE)
    mpm_log(MPM_LOG_ERROR,
            "%s: cannot read it as a case file: it is larger than %d MiB; a case file is a "
            "few kB of text: check the path",
            show(path).s, MAX_CASE_BYTES >> 20);
  else
    mpm_log(MPM_LOG_ERROR, "cannot read case file '%s': %s; check the path", path, strerror(why));
}

/* Broadcast the text in pieces that fit an int count. */
static int bcast_text(MPI_Comm comm, char *text, size_t len) {
  for (size_t off = 0; off < len;) {
    size_t piece = len - off < (size_t)INT_MAX ? len - off : (size_t)INT_MAX;
    MPM_CALL_MPI(MPI_Bcast(text + off, (int)piece, MPI_CHAR, 0, comm));
    off += piece;
  }
  return 0;
}

/* Every rank gets the file's text; a file rank 0 cannot read fails on every rank. */
static int share_file(MPI_Comm comm, const char *path, char **text, size_t *len) {
  int rank;
  long long head[2] = {0, 0}; /* length or -1, why (see slurp) */
  const char *kind = "";
  MPM_CALL_MPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) {
    int err = slurp(path, text, len, &kind);
    head[0] = err ? -1 : (long long)*len;
    head[1] = err;
  }
  MPM_CALL_MPI(MPI_Bcast(head, 2, MPI_LONG_LONG, 0, comm));
  if (head[0] < 0) {
    cannot_read(path, (int)head[1], kind); /* logged by rank 0, which knows the kind */
    return MPM_ERR_FILE;
  }
  if (rank != 0) {
    *len = (size_t)head[0];
    MPM_ALLOC(*text, *len + 1);
  }
  int rc = bcast_text(comm, *text, *len);
  if (rc) free(*text), *text = NULL;
  return rc;
}

static char *dirname_of(const char *path) {
  const char *slash = strrchr(path, '/');
  if (!slash) return strdup(".");
  return dup_n(path, slash == path ? 1 : (size_t)(slash - path));
}

/* A NUL byte would silently end the text early: refuse the file instead. */
static int check_nul(const char *path, const char *text, size_t len) {
  const char *nul = memchr(text, '\0', len);
  if (!nul) return 0;
  int line = 1;
  for (const char *p = text; p < nul; ++p) line += *p == '\n';
  mpm_log(MPM_LOG_ERROR, "%s:%d: contains a NUL byte; a case file is text", path, line);
  return MPM_ERR_INPUT;
}

int mpm_config_read_file(mpm_config *cfg, const char *path) {
  char *text = NULL;
  size_t len = 0;
  MPM_CALL(share_file(cfg->comm, path, &text, &len));
  int rc = check_nul(path, text, len);
  char *dir = rc ? NULL : dirname_of(path);
  if (!rc && !dir) rc = MPM_ERR_MEMORY;
  if (!rc) rc = mpm_config_read_string(cfg, text, path, dir);
  free(dir);
  free(text);
  return rc ? mpm_trace(__FILE__, __LINE__, __func__, rc) : 0;
}

int mpm_config_override(mpm_config *cfg, const char *assignment) {
  const char *eq = strchr(assignment, '='), *k = assignment, *v = eq ? eq + 1 : "";
  size_t kn = eq ? (size_t)(eq - k) : 0, vn = strlen(v);
  trim(&k, &kn);
  if (!eq || !dotted_ok(k, kn, 0) || !memchr(k, '.', kn) || strchr(v, '\n')) {
    if (error_room(cfg, "command line"))
      mpm_log(MPM_LOG_ERROR,
              "command line: expected key=value, got '%s'; keys name their section, as in "
              "time.t_end=0.01",
              show(assignment).s);
    return MPM_ERR_INPUT;
  }
  trim(&v, &vn);
  cut_comment(v, &vn);
  trim(&v, &vn);
  char *key = dup_n(k, kn), *value = dup_n(v, vn);
  if (!cfg->cmdline_source) cfg->cmdline_source = ++cfg->nsources;
  place at = {"command line", NULL, 0, cfg->cmdline_source, NULL};
  int rc = key && value ? set_entry(cfg, key, value, &at) : MPM_ERR_MEMORY;
  free(key), free(value);
  return rc ? mpm_trace(__FILE__, __LINE__, __func__, rc) : 0;
}

int mpm_config_set(mpm_config *cfg, const char *key, const char *value, const char *where) {
  place at = {where, NULL, 0, ++cfg->nsources, NULL};
  MPM_CALL(set_entry(cfg, key, value, &at));
  return 0;
}

/* ---- validation ---------------------------------------------------------------------- */

/* Levenshtein distance, letters compared without case (a wrong case is a near miss), or
 * limit + 1 if it exceeds limit. Only a band of width 2 limit + 1 is computed, so a long
 * garbage key costs length x limit, not length squared. */
static size_t edit_distance(const char *a, const char *b, size_t limit) {
  size_t na = strlen(a), nb = strlen(b), inf = limit + 1;
  if ((na > nb ? na - nb : nb - na) > limit) return inf;
  size_t *row = malloc((nb + 1) * sizeof *row);
  if (!row) return inf;
  for (size_t j = 0; j <= nb; ++j) row[j] = j <= limit ? j : inf;
  for (size_t i = 1; i <= na; ++i) {
    size_t lo = i > limit ? i - limit : 1, hi = i + limit < nb ? i + limit : nb;
    size_t diag = row[lo - 1];
    row[lo - 1] = lo == 1 && i <= limit ? i : inf; /* column lo - 1 leaves the band */
    size_t best_row = row[lo - 1];
    for (size_t j = lo; j <= hi; ++j) {
      size_t up = row[j];
      size_t d = diag + (tolower((unsigned char)a[i - 1]) != tolower((unsigned char)b[j - 1]));
      if (up + 1 < d) d = up + 1;
      if (row[j - 1] + 1 < d) d = row[j - 1] + 1;
      row[j] = d < inf ? d : inf;
      diag = up;
      if (row[j] < best_row) best_row = row[j];
    }
    if (best_row > limit) { /* the distance can only grow from here */
      free(row);
      return inf;
    }
  }
  size_t d = row[nb] < inf ? row[nb] : inf;
  free(row);
  return d;
}

/* The spec key with each "*" replaced by key's component at the same place. */
static char *instantiate(const char *pat, const char *key) {
  sbuf b = {0};
  for (;;) {
    size_t pl = strcspn(pat, "."), kl = strcspn(key, ".");
    if (is_star(pat, pl) && kl)
      sb_add(&b, key, kl);
    else
      sb_add(&b, pat, pl);
    pat += pl, key += kl;
    if (!*pat) break;
    sb_add(&b, ".", 1);
    ++pat;
    if (*key) ++key;
  }
  return sb_take(&b);
}

/* The valid key nearest to key, if it is near enough to be a likely typo; else NULL. A key
 * longer than SUGGEST_MAX is no typo of one, and comparing it with every spec would cost its
 * length times the specs (a 15 MB key took 39 s). */
enum { SUGGEST_MAX = 512 };
static char *nearest_key(const mpm_config *cfg, const char *key) {
  /* A third of the key, at least 2 and at most 8: beyond that it is no typo. */
  size_t len = strlen(key), limit = len / 3 < 2 ? 2 : len / 3 > 8 ? 8 : len / 3;
  size_t best_d = SIZE_MAX;
  char *best = NULL;
  if (len > SUGGEST_MAX) return NULL;
  for (size_t i = 0; i < cfg->nspecs; ++i) {
    char *cand = instantiate(cfg->specs[i]->key, key);
    size_t d = cand ? edit_distance(key, cand, limit) : SIZE_MAX;
    if (d <= limit && d < best_d) {
      free(best);
      best = cand, best_d = d;
    } else
      free(cand);
  }
  return best;
}

/* "dx, lo, hi": the keys of the schema section that key names, if there is one. */
static char *section_keys(const mpm_config *cfg, const char *key) {
  sbuf b = {0};
  for (size_t i = 0; i < cfg->nspecs; ++i) {
    const char *sk = cfg->specs[i]->key;
    size_t n = section_len(sk);
    if (section_in(key, sk, n) != section_len(key)) continue;
    if (b.len) sb_add(&b, ", ", 2);
    sb_str(&b, sk + n + 1);
  }
  return b.len ? sb_take(&b) : (free(b.s), NULL);
}

static void unknown_key(const mpm_config *cfg, const entry *e) {
  if (!error_room(cfg, e->where)) return;
  char *near = nearest_key(cfg, e->key), *keys = near ? NULL : section_keys(cfg, e->key);
  if (near)
    mpm_log(MPM_LOG_ERROR, "%s: unknown key '%s'; did you mean '%s'?", e->where, show(e->key).s,
            show(near).s);
  else if (keys)
    mpm_log(MPM_LOG_ERROR, "%s: unknown key '%s'; [%s] has: %s", e->where, show(e->key).s,
            show_n(e->key, section_len(e->key)).s, keys);
  else
    mpm_log(MPM_LOG_ERROR, "%s: unknown key '%s'; no section or key of that name exists", e->where,
            show(e->key).s);
  free(near), free(keys);
}

/* 1 if the section of key (all of it up to the last dot) is a section of the schema. */
static int section_known(const mpm_config *cfg, const char *key) {
  const size_t len = section_len(key);
  for (size_t i = 0; len && i < cfg->nspecs; ++i) {
    const char *sk = cfg->specs[i]->key;
    if (section_in(key, sk, section_len(sk)) == len) return 1;
  }
  return 0;
}

/* The schema's section names ("run, domain, ..., solid.NAME"), each once, in order. */
static char *section_names(const mpm_config *cfg) {
  sbuf b = {0};
  for (size_t i = 0; i < cfg->nspecs; ++i) {
    const char *sk = cfg->specs[i]->key;
    const size_t n = section_len(sk);
    int seen = 0;
    for (size_t j = 0; j < i && !seen; ++j)
      seen = section_len(cfg->specs[j]->key) == n && memcmp(cfg->specs[j]->key, sk, n) == 0;
    if (seen) continue;
    if (b.len) sb_add(&b, ", ", 2);
    for (size_t k = 0; k < n;) { /* component by component, "*" as NAME */
      size_t c = strcspn(sk + k, ".");
      if (c > n - k) c = n - k;
      if (is_star(sk + k, c))
        sb_str(&b, "NAME");
      else
        sb_add(&b, sk + k, c);
      k += c;
      if (k < n) sb_add(&b, ".", 1), ++k;
    }
  }
  return sb_take(&b);
}

/* The schema section nearest to sec[0..len), with its instance names taken from sec, if it is
 * near enough to be a likely typo; else NULL. */
static char *nearest_section(const mpm_config *cfg, const char *sec, size_t len) {
  size_t limit = len / 3 < 2 ? 2 : len / 3 > 8 ? 8 : len / 3, best_d = SIZE_MAX;
  char *name = dup_n(sec, len), *best = NULL;
  for (size_t i = 0; name && i < cfg->nspecs; ++i) {
    char *pat = dup_n(cfg->specs[i]->key, section_len(cfg->specs[i]->key));
    char *cand = pat ? instantiate(pat, name) : NULL;
    const size_t d = cand && !strchr(cand, '*') ? edit_distance(name, cand, limit) : SIZE_MAX;
    free(pat);
    if (d <= limit && d < best_d)
      free(best), best = cand, best_d = d;
    else
      free(cand);
  }
  free(name);
  return best;
}

/* One line for a section the schema does not have, at its first key: the section named, and
 * the nearest valid one or, when none is near, the sections there are. */
static void unknown_section(const mpm_config *cfg, const entry *e) {
  if (!error_room(cfg, e->where)) return;
  const size_t len = section_len(e->key);
  for (size_t i = 0; i < cfg->nspecs; ++i) { /* [solid] for [solid.NAME] */
    const char *sk = cfg->specs[i]->key;
    if (section_len(sk) == len + 2 && memcmp(sk, e->key, len) == 0 && sk[len] == '.' &&
        sk[len + 1] == '*') {
      mpm_log(MPM_LOG_ERROR, "%s: section '[%s]' needs a name: write '[%s.NAME]'", e->where,
              show_n(e->key, len).s, show_n(e->key, len).s);
      return;
    }
  }
  char *near = nearest_section(cfg, e->key, len), *all = near ? NULL : section_names(cfg);
  if (near)
    mpm_log(MPM_LOG_ERROR, "%s: unknown section '[%s]'; did you mean '[%s]'?", e->where,
            show_n(e->key, len).s, show(near).s);
  else
    mpm_log(MPM_LOG_ERROR, "%s: unknown section '[%s]'; the sections are %s", e->where,
            show_n(e->key, len).s, all ? all : "listed by 'mpmfsi keys'");
  free(near), free(all);
}

/* An entry whose key the schema lacks: one line per unknown section (at its first key, or the
 * first after another section's), else one per key. */
static void unknown_entry(const mpm_config *cfg, size_t i) {
  const entry *e = &cfg->entries[i];
  if (section_known(cfg, e->key)) {
    unknown_key(cfg, e);
    return;
  }
  const size_t len = section_len(e->key);
  const char *prev = i > 0 ? cfg->entries[i - 1].key : NULL;
  if (prev && section_len(prev) == len && memcmp(prev, e->key, len) == 0) return;
  unknown_section(cfg, e);
}

/* The first instance name ("*" of the spec pattern) in key longer than MPM_CONFIG_NAME_MAX:
 * its length, and its start in *name; 0 if there is none. */
static size_t long_name(const char *pat, const char *key, const char **name) {
  for (;;) {
    const size_t pl = strcspn(pat, "."), kl = strcspn(key, ".");
    if (is_star(pat, pl) && kl > MPM_CONFIG_NAME_MAX) {
      *name = key;
      return kl;
    }
    pat += pl, key += kl;
    if (!*pat || !*key) return 0;
    ++pat, ++key;
  }
}

/* An instance name over the limit: one line per section (at its first key, or the first after
 * another section's). Returns 1 if entry i has one. */
static int name_too_long(const mpm_config *cfg, const mpm_key_spec *sp, size_t i) {
  const entry *e = &cfg->entries[i];
  const char *name = NULL;
  const size_t n = long_name(sp->key, e->key, &name), len = section_len(e->key);
  if (!n) return 0;
  const char *prev = i > 0 ? cfg->entries[i - 1].key : NULL;
  if (prev && section_len(prev) == len && memcmp(prev, e->key, len) == 0) return 1;
  if (error_room(cfg, e->where))
    mpm_log(MPM_LOG_ERROR,
            "%s: the name in '[%.*s...]' is %zu characters long; a name may have at most %d: "
            "choose a shorter one",
            e->where, (int)(name - e->key) + 16, show_n(e->key, len).s, n, MPM_CONFIG_NAME_MAX);
  return 1;
}

/* 1 if entry j is the first entry of the section (matching pat[0..plen)) that it lies in. */
static int first_in_section(const mpm_config *cfg, size_t j, const char *pat, size_t plen) {
  const char *key = cfg->entries[j].key;
  size_t len = section_in(key, pat, plen);
  /* Sections are mostly contiguous: looking at the entry before first keeps this O(1). */
  for (size_t i = j ? j - 1 : 0; i < j; ++i)
    if (section_in(cfg->entries[i].key, pat, plen) == len &&
        memcmp(cfg->entries[i].key, key, len) == 0)
      return 0;
  for (size_t i = 0; i < j; ++i)
    if (section_in(cfg->entries[i].key, pat, plen) == len &&
        memcmp(cfg->entries[i].key, key, len) == 0)
      return 0;
  return 1;
}

static int section_has(const mpm_config *cfg, const char *sec, size_t len, const char *last) {
  for (size_t i = 0; i < cfg->n; ++i) {
    const char *k = cfg->entries[i].key;
    if (strncmp(k, sec, len) == 0 && k[len] == '.' && strcmp(k + len + 1, last) == 0) return 1;
  }
  return 0;
}

/* A key without a default that is not marked optional must be set in every section used. */
static int is_required(const mpm_key_spec *sp) {
  return !sp->def && !sp->optional;
}

/* Every used section that lacks the required key sp: one message each. */
static int check_required(const mpm_config *cfg, const mpm_key_spec *sp) {
  size_t plen = section_len(sp->key);
  const char *last = sp->key + plen + 1;
  int bad_any = 0;
  for (size_t j = 0; j < cfg->n; ++j) {
    const entry *e = &cfg->entries[j];
    size_t len = section_in(e->key, sp->key, plen);
    if (!len || !first_in_section(cfg, j, sp->key, plen) || section_has(cfg, e->key, len, last))
      continue;
    if (error_room(cfg, e->where))
      mpm_log(MPM_LOG_ERROR, "%s: [%s] lacks the required key '%s'%s%s%s; add '%s = ...' to it",
              e->where, show_n(e->key, len).s, last, PAREN(help_of(sp)), last);
    bad_any = 1;
  }
  return bad_any;
}

int mpm_config_validate(const mpm_config *cfg) {
  int bad_any = 0;
  errors_flush(cfg);
  for (size_t i = 0; i < cfg->n; ++i) {
    const entry *e = &cfg->entries[i];
    const mpm_key_spec *sp = find_spec(cfg, e->key);
    item it = entry_item(cfg, sp, e);
    if (!sp)
      unknown_entry(cfg, i), bad_any = 1;
    else if (strchr(sp->key, '*') && name_too_long(cfg, sp, i))
      bad_any = 1;
    else if (check_value(&it) != 0)
      bad_any = 1;
  }
  for (size_t i = 0; i < cfg->nspecs; ++i)
    if (is_required(cfg->specs[i]) && check_required(cfg, cfg->specs[i])) bad_any = 1;
  errors_flush(cfg);
  return bad_any ? mpm_trace(__FILE__, __LINE__, __func__, MPM_ERR_INPUT) : 0;
}

/* ---- getters ------------------------------------------------------------------------- */

static const char *const g_type_names[] = {"real", "int",   "bool",  "string",
                                           "enum", "reals", "names", "path"};

/* The checked value of key, if its type is one of the mask's (1 << type) bits. */
static int lookup(const mpm_config *cfg, const char *key, unsigned types, item *it) {
  const mpm_key_spec *sp = find_spec(cfg, key);
  if (!sp) MPM_FAIL(MPM_ERR_INPUT, "internal error: '%s' is not a key of the schema", show(key).s);
  if (!(types & (1u << sp->type)))
    MPM_FAIL(MPM_ERR_INTERNAL, "internal error: '%s' is a %s key, read as another type",
             show(key).s, g_type_names[sp->type]);
  const entry *e = find_entry(cfg, key);
  if (e)
    *it = entry_item(cfg, sp, e);
  else if (sp->def)
    *it = (item){cfg, sp, key, sp->def, sp->def, NULL, 0, 1};
  else {
    size_t n = section_len(key);
    mpm_log(MPM_LOG_ERROR, "missing required key '%s'%s%s%s; add '%s = ...' under [%s]",
            show(key).s, PAREN(help_of(sp)), key + n + 1, show_n(key, n).s);
    return MPM_ERR_INPUT;
  }
  return check_value(it);
}

#define TYPE_BIT(t) (1u << (t))

int mpm_config_get_real(const mpm_config *cfg, const char *key, double *value) {
  item it;
  MPM_CALL(lookup(cfg, key, TYPE_BIT(MPM_KEY_REAL) | TYPE_BIT(MPM_KEY_INT), &it));
  return parse_real(it.value, strlen(it.value), value) == 0 ? 0 : MPM_ERR_INTERNAL;
}

int mpm_config_get_int(const mpm_config *cfg, const char *key, int *value) {
  item it;
  MPM_CALL(lookup(cfg, key, TYPE_BIT(MPM_KEY_INT), &it));
  return parse_int(it.value, value) == 0 ? 0 : MPM_ERR_INTERNAL;
}

int mpm_config_get_bool(const mpm_config *cfg, const char *key, int *value) {
  item it;
  MPM_CALL(lookup(cfg, key, TYPE_BIT(MPM_KEY_BOOL), &it));
  return parse_bool(it.value, value) == 0 ? 0 : MPM_ERR_INTERNAL;
}

int mpm_config_get_string(const mpm_config *cfg, const char *key, const char **value) {
  item it;
  MPM_CALL(lookup(cfg, key,
                  TYPE_BIT(MPM_KEY_STRING) | TYPE_BIT(MPM_KEY_ENUM) | TYPE_BIT(MPM_KEY_NAMES) |
                      TYPE_BIT(MPM_KEY_PATH),
                  &it));
  *value = it.sp->type == MPM_KEY_PATH ? it.path : it.value;
  return 0;
}

int mpm_config_get_reals(const mpm_config *cfg, const char *key, double *values, int max,
                         int *count) {
  item it;
  size_t pos = 0, n;
  const char *s;
  MPM_CALL(lookup(cfg, key, TYPE_BIT(MPM_KEY_REALS) | TYPE_BIT(MPM_KEY_REAL), &it));
  *count = 0;
  while (next_item(it.value, &pos, &s, &n)) {
    if (*count == max) return bad(&it, "too many values: at most %d are read", max);
    if (parse_real(s, n, &values[*count]) != 0) return MPM_ERR_INTERNAL;
    ++*count;
  }
  return 0;
}

int mpm_config_has(const mpm_config *cfg, const char *key) {
  return find_entry(cfg, key) != NULL;
}

int mpm_config_set_off_default(const mpm_config *cfg, const mpm_key_spec *sp) {
  if (!mpm_config_has(cfg, sp->key)) return 0;
  if (!sp->def) return 1;
  if (sp->type == MPM_KEY_REAL || sp->type == MPM_KEY_INT) {
    double v = 0.0;
    return mpm_config_get_real(cfg, sp->key, &v) != 0 || v != strtod(sp->def, NULL);
  }
  const char *v = NULL;
  return mpm_config_get_string(cfg, sp->key, &v) != 0 || strcmp(v, sp->def) != 0;
}

void mpm_config_enum_text(char *choices, size_t nchoices, char *help, size_t nhelp,
                          const char *intro, const char *const *name, const char *const *help_of,
                          int n) {
  size_t used = 0, hused = (size_t)snprintf(help, nhelp, "%s", intro);
  choices[0] = '\0';
  for (int k = 0; k < n; ++k) {
    if (used < nchoices)
      used += (size_t)snprintf(choices + used, nchoices - used, "%s%s", k ? "|" : "", name[k]);
    if (hused < nhelp)
      hused += (size_t)snprintf(help + hused, nhelp - hused, " %s (%s)%s", name[k], help_of[k],
                                k + 1 < n ? ";" : "");
  }
}

const char *mpm_config_where(const mpm_config *cfg, const char *key) {
  const entry *e = find_entry(cfg, key);
  return e ? e->where : "default";
}

/* ---- instances ----------------------------------------------------------------------- */

/* The instance names under prefix (prefix.NAME.key), in order of first appearance. */
static int collect_names(const mpm_config *cfg, const char *prefix, name_list *out) {
  size_t plen = strlen(prefix);
  MPM_ALLOC(out->names, cfg->n); /* at most one name per entry */
  for (size_t i = 0; i < cfg->n; ++i) {
    const char *k = cfg->entries[i].key, *name = k + plen + 1;
    if (strncmp(k, prefix, plen) != 0 || k[plen] != '.') continue;
    size_t len = strcspn(name, ".");
    if (!name[len]) continue; /* prefix.key, not prefix.NAME.key */
    int seen = 0;
    for (int j = 0; j < out->count && !seen; ++j)
      seen = strlen(out->names[j]) == len && memcmp(out->names[j], name, len) == 0;
    if (seen) continue;
    if (!(out->names[out->count] = dup_n(name, len)))
      MPM_FAIL(MPM_ERR_MEMORY, "out of memory listing instances");
    out->count++;
  }
  return 0;
}

static int same_list(const name_list *a, const name_list *b) {
  if (strcmp(a->prefix, b->prefix) != 0 || a->count != b->count) return 0;
  for (int i = 0; i < a->count; ++i)
    if (strcmp(a->names[i], b->names[i]) != 0) return 0;
  return 1;
}

/* The cached copy of l, adding l if there is none. On success l belongs to the cache. */
static int cache_list(mpm_config *c, name_list *l, char ***names) {
  for (size_t i = 0; i < c->nlists; ++i)
    if (same_list(&c->lists[i], l)) {
      free_names(l);
      *names = c->lists[i].names;
      return 0;
    }
  RESERVE(c->lists, c->nlists + 1, c->cap_lists);
  c->lists[c->nlists++] = *l;
  *names = l->names;
  return 0;
}

int mpm_config_instances(const mpm_config *cfg, const char *prefix, const char *const **names,
                         int *count) {
  /* A list handed out must live as long as cfg, so cfg keeps it: a logically const cache.
   * The cast is sound: mpm_config_new allocates cfg, it is never defined const. */
  mpm_config *c = (mpm_config *)cfg;
  name_list l = {strdup(prefix), NULL, 0};
  char **kept = NULL;
  int rc = l.prefix ? collect_names(cfg, prefix, &l) : MPM_ERR_MEMORY;
  if (!rc) rc = cache_list(c, &l, &kept);
  if (rc) {
    free_names(&l);
    return mpm_trace(__FILE__, __LINE__, __func__, rc);
  }
  *names = (const char *const *)kept;
  *count = l.count;
  return 0;
}

/* ---- reporting a consumer's problem -------------------------------------------------- */

/* A key that is not set, or a section name: locate it by the first entry inside it. */
/* Where the first entry of the section that key lies in was set, or NULL. */
static const char *section_where(const mpm_config *cfg, const char *key) {
  size_t sec = section_len(key);
  for (size_t i = 0; sec && i < cfg->n; ++i) {
    const entry *e = &cfg->entries[i];
    if (strncmp(e->key, key, sec) == 0 && e->key[sec] == '.') return e->where;
  }
  return NULL;
}

static void fail_unset(const mpm_config *cfg, const char *key, const char *msg) {
  size_t n = strlen(key);
  for (size_t i = 0; i < cfg->n; ++i) {
    const entry *e = &cfg->entries[i];
    if (strncmp(e->key, key, n) == 0 && e->key[n] == '.') {
      if (error_room(cfg, e->where))
        mpm_log(MPM_LOG_ERROR, "%s: [%s]: %s", e->where, show(key).s, msg);
      return;
    }
  }
  const char *where = section_where(cfg, key);
  if (!error_room(cfg, where))
    return;
  else if (where)
    mpm_log(MPM_LOG_ERROR, "%s: %s: %s", where, show(key).s, msg);
  else
    mpm_log(MPM_LOG_ERROR, "%s: %s", show(key).s, msg);
}

int mpm_config_fail(const mpm_config *cfg, const char *key, const char *fmt, ...) {
  sbuf b = {0};
  va_list ap;
  va_start(ap, fmt);
  sb_vprintf(&b, fmt, ap);
  va_end(ap);
  const char *msg = b.failed ? fmt : b.s;
  const entry *e = find_entry(cfg, key);
  const mpm_key_spec *sp = find_spec(cfg, key);
  /* A default is located by its section, when that is set somewhere. */
  item it = {cfg, sp, key, sp ? sp->def : NULL, NULL, section_where(cfg, key), 0, 1};
  if (e) it = entry_item(cfg, sp, e);
  if (it.value)
    report(&it, msg, 0); /* the consumer's message says enough: no help text */
  else
    fail_unset(cfg, key, msg);
  free(b.s);
  return MPM_ERR_INPUT;
}

/* ---- resolved text ------------------------------------------------------------------- */

typedef struct {
  sbuf b;
  const mpm_config *cfg;
  char *cwd; /* NULL if unknown */
} emitter;

static char *current_dir(void) {
  for (size_t size = 256; size < ((size_t)1 << 20); size *= 2) {
    char *buf = malloc(size);
    if (!buf) return NULL;
    if (getcwd(buf, size)) return buf;
    free(buf);
    if (errno != ERANGE) return NULL;
  }
  return NULL;
}

/* Paths are written absolute, so the text names the same files wherever it is read. */
static void emit_path(emitter *em, const char *path) {
  if (path[0] && path[0] != '/' && em->cwd) {
    sb_str(&em->b, em->cwd);
    if (strcmp(em->cwd, "/") != 0) sb_add(&em->b, "/", 1);
  }
  sb_str(&em->b, path);
}

/* "last = value   # where" for spec sp in section sec, if sp is the spec of that key; a
 * default as a comment, "# last = value   # default", which reading back leaves unset (a
 * default written as a value would count as set, and may not apply to the instance). */
static void emit_key(emitter *em, const mpm_key_spec *sp, const char *sec, size_t slen,
                     int *header) {
  const char *last = sp->key + section_len(sp->key) + 1;
  sbuf k = {0};
  sb_add(&k, sec, slen);
  sb_add(&k, ".", 1);
  sb_str(&k, last);
  const entry *e = k.failed ? NULL : find_entry(em->cfg, k.s);
  if (k.failed)
    em->b.failed = 1;
  else if (find_spec(em->cfg, k.s) == sp && (e || sp->def)) {
    if (!*header) {
      sb_str(&em->b, "\n[");
      sb_add(&em->b, sec, slen);
      sb_str(&em->b, "]\n");
      *header = 1;
    }
    sb_printf(&em->b, "%s%s = ", e ? "" : "# ", last);
    if (sp->type == MPM_KEY_PATH)
      emit_path(em, e ? e->path : sp->def);
    else
      sb_str(&em->b, e ? e->value : sp->def);
    sb_printf(&em->b, "   # %s\n", e ? show(e->from ? e->from : e->where).s : "default");
  }
  free(k.s);
}

static int same_section(const char *a, const char *b) {
  size_t n = section_len(a);
  return n == section_len(b) && memcmp(a, b, n) == 0;
}

/* Section sec, an instance of the section of spec i: every key its specs declare. The
 * header is written with the first key, so that no empty section appears. */
static void emit_section(emitter *em, size_t i, const char *sec, size_t slen) {
  const mpm_config *cfg = em->cfg;
  int header = 0;
  for (size_t k = i; k < cfg->nspecs; ++k)
    if (same_section(cfg->specs[k]->key, cfg->specs[i]->key))
      emit_key(em, cfg->specs[k], sec, slen, &header);
}

static int section_seen(const mpm_config *cfg, size_t i) {
  for (size_t j = 0; j < i; ++j)
    if (same_section(cfg->specs[j]->key, cfg->specs[i]->key)) return 1;
  return 0;
}

static int section_used(const mpm_config *cfg, const char *pat, size_t plen) {
  for (size_t j = 0; j < cfg->n; ++j)
    if (section_in(cfg->entries[j].key, pat, plen)) return 1;
  return 0;
}

static int section_requires(const mpm_config *cfg, size_t i) {
  for (size_t k = i; k < cfg->nspecs; ++k)
    if (is_required(cfg->specs[k]) && same_section(cfg->specs[k]->key, cfg->specs[i]->key))
      return 1;
  return 0;
}

/* Schema sections in declaration order; an instance section once per instance in use. An
 * unused section with required keys is left out: its defaults would put it in use when the
 * text is read back, and it would then lack those keys. */
static void emit_all(emitter *em) {
  const mpm_config *cfg = em->cfg;
  for (size_t i = 0; i < cfg->nspecs; ++i) {
    const char *pat = cfg->specs[i]->key;
    size_t plen = section_len(pat);
    if (section_seen(cfg, i)) continue;
    if (!memchr(pat, '*', plen)) {
      if (section_used(cfg, pat, plen) || !section_requires(cfg, i)) emit_section(em, i, pat, plen);
    } else
      for (size_t j = 0; j < cfg->n; ++j) {
        size_t len = section_in(cfg->entries[j].key, pat, plen);
        if (len && first_in_section(cfg, j, pat, plen))
          emit_section(em, i, cfg->entries[j].key, len);
      }
  }
}

int mpm_config_resolved_text(const mpm_config *cfg, char **text) {
  emitter em = {{0}, cfg, current_dir()};
  sb_printf(&em.b,
            "%s every key of every section in use, defaults commented out; the comment after "
            "a value says where it came from.\n",
            g_resolved_header);
  emit_all(&em);
  free(em.cwd);
  *text = sb_take(&em.b);
  if (!*text) MPM_FAIL(MPM_ERR_MEMORY, "out of memory writing the resolved configuration");
  return 0;
}
