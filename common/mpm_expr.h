/* Vector fields given as expressions in a case file ("0.1*sin(pi*x/50); 0"), one expression
 * per component separated by ';', in the variables x, y, z (GNU libmatheval evaluates
 * them; pi and e are known constants). */
#ifndef MPM_EXPR_H
#define MPM_EXPR_H

#include "mpm_config.h"
#include "mpm_types.h"

typedef struct mpm_expr mpm_expr;

/* Parse key's value into ncomp components; a syntax error, a wrong number of components, an
 * unknown variable, or a component too large for libmatheval to parse safely (over 4096
 * characters, 1000 operators or 100 nested parentheses: see mpm_expr.c) is an input error
 * naming the key. */
int mpm_expr_from_config(mpm_expr **e, const mpm_config *cfg, const char *key, int ncomp);
void mpm_expr_destroy(mpm_expr **e);
/* Component c at point x (3 coordinates; unused ones 0). NaN and infinities come out as
 * they are (1/0, sqrt(-1), log(0)): check them with mpm_expr_check_finite. */
double mpm_expr_eval(const mpm_expr *e, int c, const double *x);

/* Collective over comm: every component of e must be finite, and zero or normal (not
 * subnormal), at the n points x (dim
 * coordinates, component-major: x[d*n + i]), skipping point i where keep[i] == 0 if keep is
 * given. Otherwise the first such point (lowest rank first) is reported as an input error
 * naming key, the value as it is (NaN, +inf or -inf), the component and the point, and
 * every rank returns MPM_ERR_INPUT. */
int mpm_expr_check_finite(const mpm_expr *e, const mpm_config *cfg, const char *key, MPI_Comm comm,
                          int dim, mpm_lidx n, const double *x, const unsigned char *keep);

/* v as a message shows it: "NaN", "+inf", "-inf", or %g. buf holds 32 bytes. */
const char *mpm_expr_value_text(double v, char *buf);

#endif
