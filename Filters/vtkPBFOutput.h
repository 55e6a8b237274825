/**
 * @class   vtkPBFOutput
 * @brief   the VTK data of vtkPBFSimulation: a frame's particles and field data, the
 *          diagnostics table, the domain's outline
 *
 * Static helpers (the algorithm holds no state here): FillParticles writes the stepper's
 * particles straight into the output arrays' memory (page-locked for the GPU when asked), the
 * vertex cells shared from frame to frame while the count stays; FrameFieldData records every
 * parameter that made the frame; DiagnosticsTable and DomainOutline (the tank and the scene's
 * obstacles) build ports 1 and 2.
 */
#ifndef vtkPBFOutput_h
#define vtkPBFOutput_h

#include "vtkSmartPointer.h"
#include "vtkType.h"

#include <map>
#include <vector>
#include <string>

class vtkCellArray;
class vtkFieldData;
class vtkPolyData;
class vtkTable;

namespace pbf
{
class Simulation;
class Stepper;
struct Box;
struct Scene;
struct FrameRow;
struct SolidPose;
struct SurfaceMesh;
}

class vtkPBFOutput
{
public:
  // The particles in the solver's (cell-sorted) order with point arrays density, lambda,
  // velocity (the active scalars and vectors) and id (the GlobalIds); `vertices` is reused
  // while the particle count stays.
  // With `liquids` (the scene names them) the point array "liquid" too.
  static void FillParticles(const pbf::Stepper& stepper, bool pinned, bool liquids,
    vtkSmartPointer<vtkCellArray>& vertices, vtkPolyData* output);

  // The parameters that produced the frame, as the solver saw them (domain included), so that a
  // reader of the output alone can recompute the density with poly6 of h and the particle mass.
  static vtkSmartPointer<vtkFieldData> FrameFieldData(
    const pbf::Simulation& simulation, int frame, double frameInterval, int substeps);

  // One row per frame (Time, Frame, the density errors, ..., Backend); LoadImbalance too for a
  // decomposed run.
  static vtkSmartPointer<vtkTable> DiagnosticsTable(
    const std::map<int, pbf::FrameRow>& rows, bool loadImbalance);

  // The 12 edges of the domain and the surfaces of every solid (the scene's boxes, spheres and
  // mesh files, and the Obstacles port's), each placed at its pose, with field data Scene and a
  // point array Solid (the solid's index in the scene, -1 on the outline). A
  // box's faces are cut in squares of about `spacing` (the part within the domain), so that a
  // point array sampled at the points (the pressure) varies over a face.
  static vtkSmartPointer<vtkPolyData> DomainOutline(const pbf::Box& box, const pbf::Scene& scene,
    const std::vector<pbf::SolidPose>& poses, double spacing);

  // The fluid's surface (port 3): its triangles, Normals, velocity (the active vectors) and
  // density (the active scalars), and field data SurfaceTriangles, SurfaceMilliseconds,
  // SurfaceBytes and SurfaceDevice (where it was made: "CPU" or the GPU's name).
  // Several liquids' surfaces as one mesh: `more`'s points, arrays and triangles after `mesh`'s.
  static void AppendMesh(const pbf::SurfaceMesh& more, pbf::SurfaceMesh& mesh);
  // The point array "liquid" of a surface made of several liquids' meshes (AppendMesh).
  static void AddLiquids(const std::vector<unsigned char>& liquid, vtkPolyData* surface);

  static vtkSmartPointer<vtkPolyData> Surface(
    const pbf::SurfaceMesh& mesh, double milliseconds, const std::string& device);

  /**
   * The loads of one diagnostics row as field data: ObstacleForce [N] and ObstacleTorque [N m]
   * (one 3-component tuple per obstacle: the mean over the frame's steps, the torque about the
   * obstacle's centre of mass) and ObstacleNames. Nothing when the row has no loads.
   */
  static void AddLoads(vtkFieldData* fieldData, const pbf::FrameRow& row);

  /**
   * The bodies the fluid moves at the row's frame as field data, one tuple per body:
   * BodyPosition (its centre of mass, m), BodyOrientation (a unit quaternion w, x, y, z from the
   * scene's pose), BodyVelocity (m/s), BodyAngularVelocity (rad/s), and BodyNames. AddLoads adds
   * them too.
   */
  static void AddBodies(vtkFieldData* fieldData, const pbf::FrameRow& row);

  static void AddValue(vtkFieldData* fieldData, const char* name, double value);
  static void AddInteger(vtkFieldData* fieldData, const char* name, vtkIdType value);
  static void AddText(vtkFieldData* fieldData, const char* name, const std::string& value);
};

#endif
