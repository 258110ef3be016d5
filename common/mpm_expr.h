/* Vector fields given as expressions in a case file ("0.1*sin(pi*x/50); 0"), one expression
 * per component separated by ';', in the variables x, y, z (GNU libmatheval evaluates
 * them; pi and e are known constants). */
#ifndef MPM_EXPR_H
#define MPM_EXPR_H

#include "mpm_config.h"

typedef struct mpm_expr mpm_expr;

/* Parse key's value into ncomp components; a syntax error, a wrong number of components or
 * an unknown variable is an input error naming the key. */
int mpm_expr_from_config(mpm_expr **e, const mpm_config *cfg, const char *key, int ncomp);
void mpm_expr_destroy(mpm_expr **e);
/* Component c at point x (3 coordinates; unused ones 0). */
double mpm_expr_eval(const mpm_expr *e, int c, const double *x);

#endif
