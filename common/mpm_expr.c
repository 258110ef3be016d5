/* Expression-valued vector fields over libmatheval (see mpm_expr.h). */
#include "mpm_expr.h"

#include "mpm_error.h"

#include <matheval.h>
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
