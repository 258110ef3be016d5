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

static int parse_component(mpm_expr *e, const mpm_config *cfg, const char *key, char *text) {
  void *f = evaluator_create(text);
  if (!f)
    return mpm_config_fail(cfg, key,
                           "cannot parse the expression '%s'; use numbers, x, y, z, "
                           "pi, e, + - * / ^ and functions such as sin, exp, sqrt",
                           text);
  e->f[e->ncomp++] = f;
  const char *bad = unknown_variable(f);
  if (bad)
    return mpm_config_fail(cfg, key, "unknown variable '%s' in '%s'; expressions may use x, y, z",
                           bad, text);
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

/* The first point of this rank where a component is not finite: its index, or -1. */
static mpm_lidx first_bad(const mpm_expr *e, int dim, mpm_lidx n, const double *x,
                          const unsigned char *keep, int *comp, double *value) {
  for (mpm_lidx i = 0; i < n; ++i) {
    if (keep && !keep[i]) continue;
    double xp[3] = {0, 0, 0};
    for (int d = 0; d < dim; ++d) xp[d] = x[(size_t)d * (size_t)n + (size_t)i];
    for (int c = 0; c < e->ncomp; ++c) {
      double v = mpm_expr_eval(e, c, xp);
      if (!isfinite(v)) {
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
  return mpm_config_fail(cfg, key,
                         "gives %s%s at %s; the field must be finite wherever it is used: "
                         "check for a division by zero, sqrt or log of a negative number or "
                         "zero, or an overflow",
                         mpm_expr_value_text(info[0], vbuf), which, at);
}
