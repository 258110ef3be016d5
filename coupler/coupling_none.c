/* `none`: the phases share the grid and do not interact (each moves through the other). For
 * comparisons and one-phase scenes; it builds no coupler work at all. */
#include "mpm_coupling.h"

static const mpm_coupling_ops none_ops = {0};

const mpm_coupling_type coupling_none = {
    .name = "none",
    .help = "no interaction: the phases pass through each other",
    .ops = &none_ops,
};
