/* The registry of built-in temporal coupling schemes. Add a scheme here with one line;
 * `monolithic`, the default, stays first. */
#include "mpm_timescheme.h"

extern const mpm_timescheme_type timescheme_monolithic;
extern const mpm_timescheme_type timescheme_staggered;
extern const mpm_timescheme_type timescheme_multirate;

static const mpm_timescheme_type *const g_types[] = {
    &timescheme_monolithic,
    &timescheme_staggered,
    &timescheme_multirate,
};

const mpm_timescheme_type *const *mpm_timescheme_types(int *n) {
  *n = (int)(sizeof g_types / sizeof g_types[0]);
  return g_types;
}
