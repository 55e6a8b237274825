// The datasets on the filter's Obstacles port as solids of the solver: the third place where
// vtkPBFSimulation translates between VTK and the solver (vtkPBFTranslate.h has the others).
#ifndef vtkPBFObstacles_h
#define vtkPBFObstacles_h

#include "Scene.h"
#include "Solids.h"

#include <string>
#include <vector>

class vtkDataSet;

// The surface of any dataset as a triangle mesh solid named `name`: poly data as it is, other
// datasets through their outer surface (vtkDataSetSurfaceFilter), polygons and strips cut into
// triangles, coincident points merged so that the triangles of a closed surface share edges.
// Lines and vertices bound nothing and are left out. `thickness` > 0 makes an open surface a thin
// shell. Throws pbf::InvalidInput naming `name` when nothing is left (an empty obstacle).
pbf::SolidRegion vtkPBFSolidFromInput(vtkDataSet* input, double thickness, const std::string& name);

// Reads the file of every mesh obstacle of a scene file ("type": "mesh") with VTK's reader for
// its extension (.stl, .obj, .ply, .vtp) into the solid's triangles. Throws pbf::InvalidInput
// naming obstacles[k].file for a missing file, an unknown extension or a file that yields no
// surface.
void vtkPBFReadMeshFiles(pbf::Scene& scene);

// The mesh files a scene file names (their paths resolved against the scene file's folder). A
// scene file that does not parse gives none here; building the run reports it.
std::vector<std::string> vtkPBFSceneMeshFiles(const std::string& sceneFile);

// The size and modification time of each file: a mesh edited in place is another run, as an
// edited scene file is.
std::string vtkPBFFileVersions(const std::vector<std::string>& files);

// What vtkPBFRigidBody wrote into an obstacle's field data: a body's density and name.
struct vtkPBFBodyTag
{
  bool Tagged = false; // PBFBodyDensity is there: the obstacle is a body
  double Density = 0;  // [kg/m^3], as typed (checked where the run is built)
  std::string Name;    // empty: the simulation names it
  bool FreeAxes[3] = { true, true, true }; // the world axes its centre moves along
  bool Turns = true;
  double Release = 0; // [s], as typed (checked where the run is built)
};
vtkPBFBodyTag vtkPBFBodyTagOf(vtkDataSet* obstacle);

#endif
