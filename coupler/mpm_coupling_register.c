/* The registry of built-in spatial coupling schemes. Add a scheme here with one line; `none`
 * stays first. */
#include "mpm_coupling.h"

extern const mpm_coupling_type coupling_none;
extern const mpm_coupling_type coupling_velocity;
extern const mpm_coupling_type coupling_contact;
extern const mpm_coupling_type coupling_traction;
extern const mpm_coupling_type coupling_sharp;

static const mpm_coupling_type *const g_types[] = {
    &coupling_none, &coupling_velocity, &coupling_contact, &coupling_traction, &coupling_sharp,
};

const mpm_coupling_type *const *mpm_coupling_types(int *n) {
  *n = (int)(sizeof g_types / sizeof g_types[0]);
  return g_types;
}
