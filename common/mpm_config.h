/* Case files: `[section]` headers and `key = value` lines, read with libinih, giving dotted
 * keys ("grid.dx"). A section name may itself be dotted to name an instance
 * ("[geometry.block]" gives "geometry.block.type").
 *
 * Every valid key is declared in a schema (mpm_key_spec tables that each module adds). A
 * spec key may contain "*" as one dotted component, matching any instance name
 * ("geometry.*.type"). Validation reports, on rank 0, one line per problem of the form
 *     case.ini:12: grid.dx = -1: must be > 0 (grid spacing, m). <what to do>
 * naming the nearest valid key for an unknown key. Command-line overrides
 * ("time.t_end=0.01") are entries like any other, with the origin "command line".
 *
 * Values are kept as text; typed getters parse them (and fall back to the spec's default).
 * All ranks hold the same entries: rank 0 reads the file and broadcasts its text. */
#ifndef MPM_CONFIG_H
#define MPM_CONFIG_H

#include <mpi.h>
#include <stdio.h>

typedef enum {
  MPM_KEY_REAL,   /* one real number */
  MPM_KEY_INT,    /* one integer */
  MPM_KEY_BOOL,   /* true/false, yes/no, on/off, 1/0 */
  MPM_KEY_STRING, /* free text */
  MPM_KEY_ENUM,   /* one of choices, "a|b|c" */
  MPM_KEY_REALS,  /* 1..max_count reals separated by blanks or commas */
  MPM_KEY_NAMES,  /* 1.. names separated by blanks or commas */
  MPM_KEY_PATH    /* a file that must exist; relative to the case file's folder */
} mpm_key_type;

typedef struct mpm_key_spec {
  const char *key; /* dotted, "*" matches one instance component */
  mpm_key_type type;
  const char *def;   /* default as text; NULL: no default (see optional) */
  double min, max;   /* inclusive range for REAL, INT and each of REALS (use -HUGE_VAL/HUGE_VAL) */
  int min_exclusive; /* 1: value must be > min rather than >= min */
  int max_count;     /* REALS: most values allowed (0 = any) */
  const char *choices; /* ENUM: "a|b|c" */
  const char *help;    /* one line: meaning, unit, what a sensible value is */
  int optional;        /* with def == NULL: 1 = may stay unset (its consumer checks
                          mpm_config_has), 0 = required in every section in use */
  const char *unit;    /* SI unit of the value ("m", "kg/m^3"), "-" for a dimensionless
                          number, NULL for text, names, choices and paths. The last member, so
                          that tables written before it need no change. */
} mpm_key_spec;

typedef struct mpm_config mpm_config;

int mpm_config_new(mpm_config **cfg, MPI_Comm comm);
void mpm_config_destroy(mpm_config **cfg);

/* Add n specs (the table must outlive cfg). */
int mpm_config_add_schema(mpm_config *cfg, const mpm_key_spec *specs, int n);

/* The schema in the order it was added (for `mpmfsi keys`): the spec number k, NULL past the
 * last one. */
const mpm_key_spec *mpm_config_spec(const mpm_config *cfg, size_t k);
/* A spec's type as a word ("real", "int", "bool", "text", "choice", "reals", "names", "path"). */
const char *mpm_config_type_name(mpm_key_type type);
/* What values a spec allows, as validation states it: "> 0", "in [0, 1]", "a|b|c", at most
 * 3 values; "" when any value of its type is allowed. Truncated to the buffer. */
void mpm_config_allowed_text(const mpm_key_spec *sp, char *buf, size_t n);

/* Read a case file: rank 0 reads it, every rank parses the same text. A missing or
 * unreadable file, one that is no regular file (a folder, device or FIFO) or larger than
 * 16 MiB, or a syntax error, is reported with the file (and line). At most 20 error lines
 * are printed per read (and per validation), then one line counting the rest. */
int mpm_config_read_file(mpm_config *cfg, const char *path);
/* Parse case text; origin names it in messages ("case.ini"), dir resolves relative paths. */
int mpm_config_read_string(mpm_config *cfg, const char *text, const char *origin, const char *dir);
/* One "key=value" override from the command line; replaces a value read from a file. The
 * command line is one source, like one file: a key given twice there is an input error
 * naming both assignments. */
int mpm_config_override(mpm_config *cfg, const char *assignment);
/* Set key to value verbatim (no comment stripping: for values the program derives, such as
 * a path), recorded as coming from `where` (a string that outlives cfg). */
int mpm_config_set(mpm_config *cfg, const char *key, const char *value, const char *where);

/* Check every entry against the schema: unknown keys (with the nearest valid key), types,
 * ranges, enum choices, file existence, required keys of every used instance. Reports
 * every problem before returning MPM_ERR_INPUT. */
int mpm_config_validate(const mpm_config *cfg);

/* Typed getters: the entry if set, else the spec's default; MPM_ERR_INPUT (with a message)
 * if the key is not in the schema, is required and missing, or does not parse. */
int mpm_config_get_real(const mpm_config *cfg, const char *key, double *value);
int mpm_config_get_int(const mpm_config *cfg, const char *key, int *value);
int mpm_config_get_bool(const mpm_config *cfg, const char *key, int *value);
/* String, enum, names and path values; the pointer stays valid while cfg lives. A path is
 * returned resolved against the case file's folder. */
int mpm_config_get_string(const mpm_config *cfg, const char *key, const char **value);
/* Up to max values; *count is how many were given. */
int mpm_config_get_reals(const mpm_config *cfg, const char *key, double *values, int max,
                         int *count);

/* 1 if the key was set in the file or on the command line. */
int mpm_config_has(const mpm_config *cfg, const char *key);
/* Is the key of spec set to something other than its default? (A checkpoint's resolved case
 * lists the defaults too, so "set" alone does not say the user chose it.) */
int mpm_config_set_off_default(const mpm_config *cfg, const mpm_key_spec *spec);

/* The text of an ENUM key over a registry of n implementations (name[k], with help[k]):
 * choices "a|b|c" and help "intro a (help a); b (help b); ...". Truncated to the buffers. */
void mpm_config_enum_text(char *choices, size_t nchoices, char *help, size_t nhelp,
                          const char *intro, const char *const *name, const char *const *help_of,
                          int n);

/* The longest instance name (the NAME of [solid.NAME]) a case may use: mpm_config_validate
 * refuses a longer one, so that modules may keep a name in a char[64] and its keys in fixed
 * buffers. */
#define MPM_CONFIG_NAME_MAX 63

/* Instance names used under a prefix, in order of first appearance: for "geometry" and
 * entries geometry.a.type, geometry.b.lo it gives {"a", "b"}. *names is owned by cfg. */
int mpm_config_instances(const mpm_config *cfg, const char *prefix, const char *const **names,
                         int *count);

/* Where a key was set: "case.ini:12", "command line", or "default". */
const char *mpm_config_where(const mpm_config *cfg, const char *key);

/* Report a problem with a key found by a consumer (a box outside the domain, say), in the
 * same one-line form as validation, on rank 0; returns MPM_ERR_INPUT. */
int mpm_config_fail(const mpm_config *cfg, const char *key, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* The resolved configuration as case-file text: every schema key of every section in use,
 * the keys that were set as "key = value   # where" and the defaults commented out
 * ("# key = value   # default"), so that reading it back sets exactly what was set (a
 * default does not count as set, and may not apply to the instance: an obstacle's
 * angle_of_attack is refused for a circle). Feeding it back in gives the same
 * configuration, and resolving that again the same text: a resolved text read back keeps
 * its "# where" comments as provenance. *text is malloc'ed. */
int mpm_config_resolved_text(const mpm_config *cfg, char **text);

#endif
