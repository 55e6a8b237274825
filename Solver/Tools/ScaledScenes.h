// Scenes scaled to a particle count, for the benchmark and the soak runs.
#pragma once

#include "Scene.h"

namespace pbf
{

// The dam_break preset (a 0.4 x 0.6 x 0.6 m column against the -x wall of a 1.6 x 0.8 x 0.6 m tank)
// widened in x and z until the column holds about `particles` lattice sites. The height stays the
// preset's: with a fixed number of Jacobi iterations the compression grows with the layers the
// solver must hold up, and a column scaled along all three axes (290 layers at 16M particles)
// compressed by 8% on average and blew up, which measures nothing useful. x and z are centred on
// the origin so that float positions round as little as possible in the wide tanks.
Scene scaledDamBreak(double particles, double spacing);

// `count` boxes of half the water's density (bodies the fluid moves) added to a scaled dam break:
// cubes of 8 spacings resting just above the floor in a row across the tank's middle (along z),
// in the surge's way.
void addFloatingBoxes(Scene& scene, int count, double spacing);

// A scaled dam break's column as two liquids: water (1000 kg/m^3) in its lower half, oil (800,
// the parameters' XSPH alpha) over it. What several liquids cost.
void splitIntoTwoLiquids(Scene& scene);

} // namespace pbf
