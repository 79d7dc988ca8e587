/* Perceptually uniform colour maps (256 sRGB entries each). */
#ifndef SURGE_RENDER_COLORMAPS_H
#define SURGE_RENDER_COLORMAPS_H

#include "surge/params.h"

typedef surge_colormap_choice surge_colormap;

const unsigned char (*surge_colormap_table(surge_colormap map))[3];

#endif
