// What a frame's particles read at points of space, as VTK data: the Probes output (a table, one
// row per probe) and the `pressure` array on the solids' surfaces of the Domain output. The sums
// are the solver's (Solver/Surface/Probes.h: poly6, the kernel the density is); a decomposed run
// adds every rank's over its own particles, in rank order, before reading them, so each rank must
// call these alike (collective when `ranks` is given).
#ifndef vtkPBFProbes_h
#define vtkPBFProbes_h

#include "vtkSmartPointer.h"
#include "vtkTable.h"

#include "Communicator.h"
#include "Parameters.h"
#include "SurfaceTypes.h"

#include <string>
#include <vector>

class vtkDataSet;
class vtkPolyData;

// One row per point of `probes` (any dataset; its points, in order): Probe (its index), Position,
// velocity [m/s], pressure [Pa], WaterHeight [m] (the wetted length above it along +y) and
// FluidFraction (1 inside the fluid, about 1/2 at a wall or the surface, 0 in air), from
// `particles` (port 0's output of the frame). A probe outside the domain gets NaN and its index
// in `outside`. `ranks`: the ranks of a decomposed run (null: this rank's particles are all).
vtkSmartPointer<vtkTable> vtkPBFProbeTable(vtkDataSet* probes, vtkPolyData* particles,
  const pbf::Parameters& parameters, pbf::distributed::Communicator* ranks,
  std::vector<vtkIdType>& outside);

// Adds the point array `pressure` [Pa] to `surfaces` (the Domain output: the tank's outline and
// the solids where they stand, its point array Solid naming each point's solid): what the
// particles press each solid with there (pbf::ParticleSums::onSolids: the boundary model's load,
// spread over the surface), 0 on the outline. `solids`: where they stand at the frame.
void vtkPBFAddSurfacePressure(vtkPolyData* surfaces, vtkPolyData* particles,
  const pbf::Parameters& parameters, const pbf::SurfaceSolids& solids,
  pbf::distributed::Communicator* ranks);

// "probe 3 at (1.2, 0.1, 0.3)" for the first few of `outside`, for the warning that names them.
std::string vtkPBFDescribeProbes(vtkDataSet* probes, const std::vector<vtkIdType>& outside);

#endif
