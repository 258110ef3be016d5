/* Expression-valued vector fields over libmatheval (see mpm_expr.h). */
#include "mpm_expr.h"

#include "mpm_error.h"

#include <limits.h>
#include <math.h>
#include <matheval.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MPM_EXPR_MAX 9

/* How large an expression may be. libmatheval parses with a bison parser, which fails cleanly
 * past 10,000 nested levels, and then walks the tree recursively (simplifying, evaluating,
 * listing the variables): a deep tree overflows the stack and the process dies. Measured
 * (libmatheval 1.1.11, a chain "x+x+...+x" or "x^x^...^x", whose tree is as deep as it has
 * terms): it survives 174,600 terms with the default 8 MiB stack, 21,600 with 1 MiB, 5,300
 * with 256 KiB (unary minuses "---x": 5,200 with 256 KiB). The tree is at most one level
 * deeper than the expression has operators and parentheses, so these limits keep it under
 * 1,100 levels: a margin of 5 at a 256 KiB stack, of 160 at the default one. A field given
 * by hand or by a fitting tool stays far below them. */
enum {
  EXPR_MAX_CHARS = 4096, /* characters of one component */
  EXPR_MAX_OPS = 1000,   /* operators + - * / ^ of one component */
  EXPR_MAX_NEST = 100    /* parentheses (and function calls) inside one another */
};

/* Quoting an expression in a message: its first characters. */
#define EXPR_SHOWN 80

struct mpm_expr {
  int ncomp;
  void *f[MPM_EXPR_MAX];
};

/* Every variable of f must be x, y or z. */
static const char *unknown_variable(void *f) {
  char **names;
  int count;
  evaluator_get_variables(f, &names, &count);
  for (int k = 0; k < count; ++k)
    if (strcmp(names[k], "x") && strcmp(names[k], "y") && strcmp(names[k], "z")) return names[k];
  return NULL;
}

/* Refuse text that libmatheval might not survive (see EXPR_MAX_CHARS), before it parses it. */
static int check_size(const mpm_config *cfg, const char *key, int comp, const char *text) {
  const size_t len = strlen(text);
  if (len > EXPR_MAX_CHARS)
    return mpm_config_fail(cfg, key,
                           "expression %d is %zu characters long, more than the limit of %d; "
                           "simplify it (a field is a short formula)",
                           comp, len, EXPR_MAX_CHARS);
  int ops = 0, nest = 0, deepest = 0;
  for (const char *c = text; *c; ++c) {
    ops += strchr("+-*/^", *c) != NULL;
    nest += *c == '(';
    if (nest > deepest) deepest = nest;
    nest -= *c == ')' && nest > 0;
  }
  if (ops > EXPR_MAX_OPS)
    return mpm_config_fail(cfg, key,
                           "expression %d has %d operators, more than the limit of %d; simplify "
                           "it (a field is a short formula)",
                           comp, ops, EXPR_MAX_OPS);
  if (deepest > EXPR_MAX_NEST)
    return mpm_config_fail(cfg, key,
                           "expression %d nests parentheses %d deep, more than the limit of %d; "
                           "simplify it",
                           comp, deepest, EXPR_MAX_NEST);
  return 0;
}

static int parse_component(mpm_expr *e, const mpm_config *cfg, const char *key, char *text) {
  MPM_CALL(check_size(cfg, key, e->ncomp + 1, text));
  void *f = evaluator_create(text);
  if (!f)
    return mpm_config_fail(cfg, key,
                           "cannot parse the expression '%.*s%s'; use numbers, x, y, z, "
                           "pi, e, + - * / ^ and functions such as sin, exp, sqrt",
                           EXPR_SHOWN, text, strlen(text) > EXPR_SHOWN ? "..." : "");
  e->f[e->ncomp++] = f;
  const char *bad = unknown_variable(f);
  if (bad)
    return mpm_config_fail(
        cfg, key, "unknown variable '%.*s' in '%.*s%s'; expressions may use x, y, z", EXPR_SHOWN,
        bad, EXPR_SHOWN, text, strlen(text) > EXPR_SHOWN ? "..." : "");
  return 0;
}

int mpm_expr_from_config(mpm_expr **ep, const mpm_config *cfg, const char *key, int ncomp) {
  const char *value;
  MPM_CALL(mpm_config_get_string(cfg, key, &value));
  mpm_expr *e;
  MPM_ALLOC(e, 1);
  *ep = e;
  char *copy = strdup(value), *save = NULL;
  if (!copy) MPM_FAIL(MPM_ERR_MEMORY, "out of memory");
  int rc = 0, n = 0;
  for (char *tok = strtok_r(copy, ";", &save); tok && !rc; tok = strtok_r(NULL, ";", &save)) {
    if (++n > ncomp || n > MPM_EXPR_MAX) break;
    rc = parse_component(e, cfg, key, tok);
  }
  free(copy);
  if (!rc && n != ncomp)
    rc = mpm_config_fail(cfg, key, "needs %d expressions separated by ';', got %d", ncomp, n);
  if (rc) {
    mpm_expr_destroy(ep);
    return mpm_trace(__FILE__, __LINE__, __func__, rc);
  }
  return 0;
}

void mpm_expr_destroy(mpm_expr **e) {
  if (!e || !*e) return;
  for (int c = 0; c < (*e)->ncomp; ++c) evaluator_destroy((*e)->f[c]);
  free(*e);
  *e = NULL;
}

double mpm_expr_eval(const mpm_expr *e, int c, const double *x) {
  char *names[3] = {"x", "y", "z"}; /* libmatheval takes non-const names */
  double v[3] = {x[0], x[1], x[2]};
  return evaluator_evaluate(e->f[c], 3, names, v);
}

const char *mpm_expr_value_text(double v, char *buf) {
  if (isnan(v)) return "NaN";
  if (isinf(v)) return v > 0 ? "+inf" : "-inf";
  snprintf(buf, 32, "%g", v);
  return buf;
}

/* A value a field may take: finite, and zero or normal (a subnormal one, below 2.2e-308 in
 * magnitude, has lost its precision; no physical field is that small). */
static int usable(double v) {
  return isfinite(v) && fpclassify(v) != FP_SUBNORMAL;
}

/* The first point of this rank where a component is not usable: its index, or -1. */
static mpm_lidx first_bad(const mpm_expr *e, int dim, mpm_lidx n, const double *x,
                          const unsigned char *keep, int *comp, double *value) {
  for (mpm_lidx i = 0; i < n; ++i) {
    if (keep && !keep[i]) continue;
    double xp[3] = {0, 0, 0};
    for (int d = 0; d < dim; ++d) xp[d] = x[(size_t)d * (size_t)n + (size_t)i];
    for (int c = 0; c < e->ncomp; ++c) {
      double v = mpm_expr_eval(e, c, xp);
      if (!usable(v)) {
        *comp = c, *value = v;
        return i;
      }
    }
  }
  return -1;
}

int mpm_expr_check_finite(const mpm_expr *e, const mpm_config *cfg, const char *key, MPI_Comm comm,
                          int dim, mpm_lidx n, const double *x, const unsigned char *keep) {
  int rank, comp = 0, who;
  double value = 0.0, info[5] = {0, 0, 0, 0, 0}; /* value, component, point */
  MPM_CALL_MPI(MPI_Comm_rank(comm, &rank));
  mpm_lidx i = first_bad(e, dim, n, x, keep, &comp, &value);
  int mine = i >= 0 ? rank : INT_MAX;
  MPM_CALL_MPI(MPI_Allreduce(&mine, &who, 1, MPI_INT, MPI_MIN, comm));
  if (who == INT_MAX) return 0;
  if (rank == who) {
    info[0] = value, info[1] = comp;
    for (int d = 0; d < dim; ++d) info[2 + d] = x[(size_t)d * (size_t)n + (size_t)i];
  }
  MPM_CALL_MPI(MPI_Bcast(info, 5, MPI_DOUBLE, who, comm));
  char vbuf[32], at[128], which[48] = "";
  int k = snprintf(at, sizeof at, "(%g", info[2]);
  for (int d = 1; d < dim && k > 0 && (size_t)k < sizeof at; ++d)
    k += snprintf(at + k, sizeof at - (size_t)k, ", %g", info[2 + d]);
  if (k > 0 && (size_t)k < sizeof at) snprintf(at + k, sizeof at - (size_t)k, ")");
  if (e->ncomp > 1) snprintf(which, sizeof which, " in component %d", (int)info[1] + 1);
  if (isfinite(info[0]))
    return mpm_config_fail(cfg, key,
                           "gives %s%s at %s, a subnormal number (smaller in magnitude than "
                           "2.2e-308, too small to compute with); the field must be 0 or at least "
                           "that large wherever it is used: check for an underflow",
                           mpm_expr_value_text(info[0], vbuf), which, at);
  return mpm_config_fail(cfg, key,
                         "gives %s%s at %s; the field must be finite wherever it is used: "
                         "check for a division by zero, sqrt or log of a negative number or "
                         "zero, or an overflow",
                         mpm_expr_value_text(info[0], vbuf), which, at);
}
