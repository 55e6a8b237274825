#include "vtkPBFOutput.h"
#include "vtkPBFPageLocked.h"

#include "vtkAbstractArray.h"
#include "vtkAppendPolyData.h"
#include "vtkCellArray.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkFloatArray.h"
#include "vtkIdTypeArray.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkOutlineSource.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkSphereSource.h"
#include "vtkStringArray.h"
#include "vtkTable.h"
#include "vtkTessellatedBoxSource.h"
#include "vtkTransform.h"
#include "vtkTransformPolyDataFilter.h"
#include "vtkTypeInt64Array.h"
#include "vtkUnsignedCharArray.h"

#include "ParameterTable.h"
#include "Parameters.h"
#include "Playback.h"
#include "Scene.h"
#include "Simulation.h"
#include "Stepper.h"
#include "SurfaceExtraction.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

namespace
{

template <class Real>
using RealArray =
  typename std::conditional<std::is_same<Real, float>::value, vtkFloatArray, vtkDoubleArray>::type;

template <class Array>
vtkSmartPointer<Array> NewArray(const char* name, int components, vtkIdType tuples)
{
  auto array = vtkSmartPointer<Array>::New();
  if (name)
  {
    array->SetName(name);
  }
  array->SetNumberOfComponents(components);
  array->SetNumberOfTuples(tuples);
  return array;
}

// Vertex cells 0..n-1 depend on the particle count only: built once per count and shared by the
// frames (outputs are never modified downstream), instead of 16 bytes per particle per frame.
vtkSmartPointer<vtkCellArray> VertexCells(vtkIdType n)
{
  auto offsets = NewArray<vtkIdTypeArray>(nullptr, 1, n + 1);
  auto connectivity = NewArray<vtkIdTypeArray>(nullptr, 1, n);
  vtkIdType* o = offsets->GetPointer(0);
  vtkIdType* c = connectivity->GetPointer(0);
  for (vtkIdType i = 0; i < n; ++i)
  {
    o[i] = i;
    c[i] = i;
  }
  o[n] = n;
  auto cells = vtkSmartPointer<vtkCellArray>::New();
  cells->SetData(offsets, connectivity);
  return cells;
}

// An output array of the given size, in page-locked memory when asked and available (the GPU
// then copies into it at the full bus speed); the array gives the memory back to the pool.
template <class Array>
vtkSmartPointer<Array> NewOutputArray(
  const char* name, int components, vtkIdType tuples, bool pinned)
{
  using Value = typename Array::ValueType;
  const auto values = static_cast<std::size_t>(tuples) * static_cast<std::size_t>(components);
  void* memory = pinned ? vtkPBFPageLocked::Allocate(values * sizeof(Value)) : nullptr;
  if (!memory)
  {
    return NewArray<Array>(name, components, tuples);
  }
  auto array = vtkSmartPointer<Array>::New();
  if (name)
  {
    array->SetName(name);
  }
  array->SetNumberOfComponents(components);
  array->SetArray(static_cast<Value*>(memory), static_cast<vtkIdType>(values), /*save=*/0,
    Array::VTK_DATA_ARRAY_USER_DEFINED);
  array->SetArrayFreeFunction(&vtkPBFPageLocked::Release);
  return array;
}

// The particles in the solver's (cell-sorted) order, read by the stepper straight into the VTK
// arrays' memory: pbf::Vec3 is three packed reals, as VTK's interleaved arrays are, and the ids
// are 64-bit like vtkIdType. No per-point call, no copy in between.
template <class Real>
void FillParticlesOf(const pbf::Stepper& stepper, bool pinned, bool liquids,
  vtkSmartPointer<vtkCellArray>& vertices, vtkPolyData* output)
{
  static_assert(sizeof(pbf::Vec3<Real>) == 3 * sizeof(Real), "pbf::Vec3 must be 3 packed reals");
  static_assert(sizeof(vtkIdType) == sizeof(std::int64_t), "particle ids are 64-bit vtkIdTypes");
  const auto n = static_cast<vtkIdType>(stepper.size());
  auto coordinates = NewOutputArray<RealArray<Real>>(nullptr, 3, n, pinned);
  auto velocity = NewOutputArray<RealArray<Real>>("velocity", 3, n, pinned);
  auto density = NewOutputArray<RealArray<Real>>("density", 1, n, pinned);
  auto lambda = NewOutputArray<RealArray<Real>>("lambda", 1, n, pinned);
  auto pressure = NewOutputArray<RealArray<Real>>("pressure", 1, n, pinned);
  auto id = NewOutputArray<vtkIdTypeArray>("id", 1, n, pinned);
  // Each particle's liquid, its index in the field data's LiquidNames, where the scene names any.
  vtkSmartPointer<vtkUnsignedCharArray> liquid =
    liquids ? NewOutputArray<vtkUnsignedCharArray>("liquid", 1, n, pinned) : nullptr;
  if (n > 0)
  {
    pbf::SnapshotView<Real> view;
    view.position = reinterpret_cast<pbf::Vec3<Real>*>(coordinates->GetPointer(0));
    view.velocity = reinterpret_cast<pbf::Vec3<Real>*>(velocity->GetPointer(0));
    view.density = density->GetPointer(0);
    view.lambda = lambda->GetPointer(0);
    view.pressure = pressure->GetPointer(0);
    view.id = reinterpret_cast<std::int64_t*>(id->GetPointer(0));
    view.liquid = liquid ? liquid->GetPointer(0) : nullptr;
    stepper.readInto(view);
  }
  if (!vertices || vertices->GetNumberOfCells() != n)
  {
    vertices = VertexCells(n);
  }

  vtkNew<vtkPoints> points;
  points->SetData(coordinates);
  output->SetPoints(points);
  output->SetVerts(vertices);

  vtkPointData* pointData = output->GetPointData();
  pointData->AddArray(density);
  pointData->AddArray(lambda);
  pointData->AddArray(pressure);
  if (liquid)
  {
    pointData->AddArray(liquid);
  }
  // Active scalars and vectors, so that a view colors by |velocity| on first show.
  pointData->SetScalars(velocity);
  pointData->SetVectors(velocity);
  pointData->SetGlobalIds(id);
}

// Per obstacle, the columns "Force <name>" [N] and "Torque <name>" [N m] (3 components: the
// frame's mean, the torque about the obstacle's centre of mass), NaN in the rows without loads
// (frame 0, a backend that sums none).
void AddLoadColumns(const std::map<int, pbf::FrameRow>& rows, vtkTable* table)
{
  std::vector<std::string> names;
  for (const auto& entry : rows)
  {
    if (entry.second.loadNames.size() > names.size())
    {
      names = entry.second.loadNames;
    }
  }
  const auto count = static_cast<vtkIdType>(rows.size());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t k = 0; k < names.size(); ++k)
  {
    auto force = NewArray<vtkDoubleArray>(("Force " + names[k]).c_str(), 3, count);
    auto torque = NewArray<vtkDoubleArray>(("Torque " + names[k]).c_str(), 3, count);
    vtkIdType r = 0;
    for (const auto& entry : rows)
    {
      const std::vector<pbf::SolidLoad>& loads = entry.second.loads;
      if (k < loads.size())
      {
        force->SetTuple3(r, loads[k].force.x, loads[k].force.y, loads[k].force.z);
        torque->SetTuple3(r, loads[k].torque.x, loads[k].torque.y, loads[k].torque.z);
      }
      else
      {
        force->SetTuple3(r, nan, nan, nan);
        torque->SetTuple3(r, nan, nan, nan);
      }
      ++r;
    }
    table->AddColumn(force);
    table->AddColumn(torque);
  }
}

// Per body the fluid moves, the columns "Position <name>" (its centre of mass, m), "Orientation
// <name>" (a unit quaternion w, x, y, z from the scene's pose), "Velocity <name>" (m/s) and
// "AngularVelocity <name>" (rad/s).
void AddBodyColumns(const std::map<int, pbf::FrameRow>& rows, vtkTable* table)
{
  if (rows.empty() || rows.begin()->second.bodies.empty())
  {
    return;
  }
  const auto count = static_cast<vtkIdType>(rows.size());
  const std::vector<pbf::FrameRow::BodyAt>& first = rows.begin()->second.bodies;
  for (std::size_t k = 0; k < first.size(); ++k)
  {
    const std::string& name = first[k].name;
    auto position = NewArray<vtkDoubleArray>(("Position " + name).c_str(), 3, count);
    auto orientation = NewArray<vtkDoubleArray>(("Orientation " + name).c_str(), 4, count);
    auto velocity = NewArray<vtkDoubleArray>(("Velocity " + name).c_str(), 3, count);
    auto spin = NewArray<vtkDoubleArray>(("AngularVelocity " + name).c_str(), 3, count);
    vtkIdType r = 0;
    for (const auto& entry : rows)
    {
      const pbf::FrameRow::BodyAt& b = entry.second.bodies.at(k);
      position->SetTuple3(r, b.centre.x, b.centre.y, b.centre.z);
      const double q[4] = { b.orientation.w, b.orientation.x, b.orientation.y, b.orientation.z };
      orientation->SetTuple(r, q);
      velocity->SetTuple3(r, b.velocity.x, b.velocity.y, b.velocity.z);
      spin->SetTuple3(r, b.angularVelocity.x, b.angularVelocity.y, b.angularVelocity.z);
      ++r;
    }
    for (vtkDoubleArray* column : { position.Get(), orientation.Get(), velocity.Get(), spin.Get() })
    {
      table->AddColumn(column);
    }
  }
}

} // namespace

//------------------------------------------------------------------------------
void vtkPBFOutput::AddLoads(vtkFieldData* fieldData, const pbf::FrameRow& row)
{
  AddBodies(fieldData, row);
  if (row.loads.empty())
  {
    return;
  }
  const auto count = static_cast<vtkIdType>(row.loads.size());
  auto force = NewArray<vtkDoubleArray>("ObstacleForce", 3, count);
  auto torque = NewArray<vtkDoubleArray>("ObstacleTorque", 3, count);
  vtkNew<vtkStringArray> names;
  names->SetName("ObstacleNames");
  names->SetNumberOfValues(count);
  for (vtkIdType k = 0; k < count; ++k)
  {
    const pbf::SolidLoad& load = row.loads[static_cast<std::size_t>(k)];
    force->SetTuple3(k, load.force.x, load.force.y, load.force.z);
    torque->SetTuple3(k, load.torque.x, load.torque.y, load.torque.z);
    names->SetValue(k, row.loadNames[static_cast<std::size_t>(k)]);
  }
  fieldData->AddArray(force);
  fieldData->AddArray(torque);
  fieldData->AddArray(names);
}

//------------------------------------------------------------------------------
void vtkPBFOutput::AddBodies(vtkFieldData* fieldData, const pbf::FrameRow& row)
{
  if (row.bodies.empty())
  {
    return;
  }
  const auto bodies = static_cast<vtkIdType>(row.bodies.size());
  auto position = NewArray<vtkDoubleArray>("BodyPosition", 3, bodies);
  auto orientation = NewArray<vtkDoubleArray>("BodyOrientation", 4, bodies);
  auto velocity = NewArray<vtkDoubleArray>("BodyVelocity", 3, bodies);
  auto spin = NewArray<vtkDoubleArray>("BodyAngularVelocity", 3, bodies);
  vtkNew<vtkStringArray> bodyNames;
  bodyNames->SetName("BodyNames");
  bodyNames->SetNumberOfValues(bodies);
  for (vtkIdType k = 0; k < bodies; ++k)
  {
    const pbf::FrameRow::BodyAt& b = row.bodies[static_cast<std::size_t>(k)];
    position->SetTuple3(k, b.centre.x, b.centre.y, b.centre.z);
    const double q[4] = { b.orientation.w, b.orientation.x, b.orientation.y, b.orientation.z };
    orientation->SetTuple(k, q);
    velocity->SetTuple3(k, b.velocity.x, b.velocity.y, b.velocity.z);
    spin->SetTuple3(k, b.angularVelocity.x, b.angularVelocity.y, b.angularVelocity.z);
    bodyNames->SetValue(k, b.name);
  }
  for (vtkAbstractArray* a :
    std::initializer_list<vtkAbstractArray*>{ position, orientation, velocity, spin, bodyNames })
  {
    fieldData->AddArray(a);
  }
}

//------------------------------------------------------------------------------
void vtkPBFOutput::AddValue(vtkFieldData* fieldData, const char* name, double value)
{
  vtkNew<vtkDoubleArray> array;
  array->SetName(name);
  array->SetNumberOfTuples(1);
  array->SetValue(0, value);
  fieldData->AddArray(array);
}

//------------------------------------------------------------------------------
void vtkPBFOutput::AddInteger(vtkFieldData* fieldData, const char* name, vtkIdType value)
{
  vtkNew<vtkIdTypeArray> array;
  array->SetName(name);
  array->SetNumberOfTuples(1);
  array->SetValue(0, value);
  fieldData->AddArray(array);
}

//------------------------------------------------------------------------------
void vtkPBFOutput::AddText(vtkFieldData* fieldData, const char* name, const std::string& value)
{
  vtkNew<vtkStringArray> array;
  array->SetName(name);
  array->SetNumberOfValues(1);
  array->SetValue(0, value);
  fieldData->AddArray(array);
}

//------------------------------------------------------------------------------
vtkSmartPointer<vtkFieldData> vtkPBFOutput::FrameFieldData(
  const pbf::Simulation& simulation, int frame, double frameInterval, int substeps)
{
  const pbf::Parameters& p = simulation.parameters();
  auto fieldData = vtkSmartPointer<vtkFieldData>::New();
  AddValue(fieldData, "SmoothingLength", p.smoothingLength());
  AddValue(fieldData, "ParticleMass", pbf::calibratedParticleMass(p));
  // Every parameter of the table under its property name (a switch or a count as an integer).
  for (const pbf::ParameterSpec& spec : pbf::parameterTable())
  {
    if (spec.type == pbf::ParameterType::Vector)
    {
      vtkNew<vtkDoubleArray> vector;
      vector->SetName(spec.property);
      vector->SetNumberOfComponents(3);
      vector->InsertNextTuple3(spec.get(p, 0), spec.get(p, 1), spec.get(p, 2));
      fieldData->AddArray(vector);
    }
    else if (spec.type == pbf::ParameterType::Real)
    {
      AddValue(fieldData, spec.property, spec.get(p, 0));
    }
    else
    {
      AddInteger(fieldData, spec.property, static_cast<vtkIdType>(spec.get(p, 0)));
    }
  }
  AddInteger(fieldData, "AdaptiveIterations", p.densityErrorTolerance > 0 ? 1 : 0);
  AddValue(fieldData, "XSPHKinematicViscosity", p.xsphNu());
  if (!p.liquids.empty())
  {
    // The point array "liquid" indexes these: the scene's liquids, their rest densities and
    // XSPH kinematic viscosities.
    vtkNew<vtkStringArray> names;
    names->SetName("LiquidNames");
    vtkNew<vtkDoubleArray> densities;
    densities->SetName("LiquidRestDensities");
    vtkNew<vtkDoubleArray> viscosities;
    viscosities->SetName("LiquidXSPHKinematicViscosities");
    for (int l = 0; l < p.liquidCount(); ++l)
    {
      names->InsertNextValue(p.liquids[static_cast<std::size_t>(l)].name);
      densities->InsertNextValue(p.liquidRestDensity(l));
      viscosities->InsertNextValue(p.liquidXsphNu(l));
    }
    fieldData->AddArray(names);
    fieldData->AddArray(densities);
    fieldData->AddArray(viscosities);
  }
  // sqrt(v0^2 + 2 |g| L): the scale of the scene's speeds, where a display's velocity color map
  // starts before the fluid moves (Plugin/vtkPBFDisplayDefaults.h).
  AddValue(fieldData, "SceneSpeed", p.sceneSpeed());
  vtkNew<vtkDoubleArray> domain;
  domain->SetName("Domain");
  domain->SetNumberOfComponents(6);
  const double bounds[6] = { p.domain.min.x, p.domain.max.x, p.domain.min.y, p.domain.max.y,
    p.domain.min.z, p.domain.max.z };
  domain->InsertNextTuple(bounds);
  fieldData->AddArray(domain);
  const bool automatic = p.timeStepping == pbf::TimeStepping::Automatic;
  AddText(fieldData, "TimeStepping", automatic ? "Automatic" : "Fixed");
  AddValue(fieldData, "TimeStep", automatic ? simulation.stepper().timeStep() : p.timeStep);
  AddValue(fieldData, "FrameInterval", frameInterval);
  AddInteger(fieldData, "SubstepsPerFrame", substeps);
  AddInteger(fieldData, "Frame", frame);
  AddInteger(fieldData, "StepCount", static_cast<vtkIdType>(simulation.stepCount()));
  // Every id given so far, and those gone through the outflows: the particles now are the
  // difference, and an id is never given twice.
  AddInteger(fieldData, "ReleasedParticles", static_cast<vtkIdType>(simulation.idCount()));
  AddInteger(fieldData, "RemovedParticles", static_cast<vtkIdType>(simulation.removedCount()));
  AddValue(fieldData, "Time", simulation.time());
  AddText(fieldData, "Backend", simulation.stepper().description());
  AddText(fieldData, "Precision", pbf::toString(simulation.stepper().precision()));
  AddText(fieldData, "Scene", simulation.scene().name);
  return fieldData;
}


//------------------------------------------------------------------------------
void vtkPBFOutput::FillParticles(const pbf::Stepper& stepper, bool pinned, bool liquids,
  vtkSmartPointer<vtkCellArray>& vertices, vtkPolyData* output)
{
  if (stepper.precision() == pbf::Precision::Double)
  {
    FillParticlesOf<double>(stepper, pinned, liquids, vertices, output);
  }
  else
  {
    FillParticlesOf<float>(stepper, pinned, liquids, vertices, output);
  }
}

//------------------------------------------------------------------------------
vtkSmartPointer<vtkTable> vtkPBFOutput::DiagnosticsTable(
  const std::map<int, pbf::FrameRow>& rows, bool loadImbalance)
{
  const auto count = static_cast<vtkIdType>(rows.size());
  auto time = NewArray<vtkDoubleArray>("Time", 1, count);
  auto frame = NewArray<vtkIdTypeArray>("Frame", 1, count);
  auto averageError = NewArray<vtkDoubleArray>("AverageDensityError", 1, count);
  auto maxError = NewArray<vtkDoubleArray>("MaxDensityError", 1, count);
  auto neighbors = NewArray<vtkDoubleArray>("AverageNeighbors", 1, count);
  auto iterations = NewArray<vtkDoubleArray>("SolverIterations", 1, count);
  auto milliseconds = NewArray<vtkDoubleArray>("MillisecondsPerStep", 1, count);
  auto substeps = NewArray<vtkDoubleArray>("Substeps", 1, count);
  auto minTimeStep = NewArray<vtkDoubleArray>("MinTimeStep", 1, count);
  auto maxTimeStep = NewArray<vtkDoubleArray>("MaxTimeStep", 1, count);
  auto maxSpeed = NewArray<vtkDoubleArray>("MaxSpeed", 1, count);
  auto kinetic = NewArray<vtkDoubleArray>("KineticEnergy", 1, count);
  auto particles = NewArray<vtkIdTypeArray>("Particles", 1, count);
  auto imbalance = NewArray<vtkDoubleArray>("LoadImbalance", 1, count);
  vtkNew<vtkStringArray> backend;
  backend->SetName("Backend");
  backend->SetNumberOfValues(count);
  vtkIdType r = 0;
  for (const auto& entry : rows)
  {
    const pbf::FrameRow& row = entry.second;
    time->SetValue(r, row.time);
    frame->SetValue(r, entry.first);
    averageError->SetValue(r, row.averageDensityError);
    maxError->SetValue(r, row.maxDensityError);
    neighbors->SetValue(r, row.averageNeighbors);
    iterations->SetValue(r, row.solverIterations);
    milliseconds->SetValue(r, row.millisecondsPerStep);
    substeps->SetValue(r, row.substeps);
    minTimeStep->SetValue(r, row.minTimeStep);
    maxTimeStep->SetValue(r, row.maxTimeStep);
    maxSpeed->SetValue(r, row.maxSpeed);
    kinetic->SetValue(r, row.kineticEnergy);
    particles->SetValue(r, static_cast<vtkIdType>(row.particles));
    imbalance->SetValue(r, row.loadImbalance);
    backend->SetValue(r, row.backend);
    ++r;
  }
  auto table = vtkSmartPointer<vtkTable>::New();
  for (vtkAbstractArray* column :
    std::initializer_list<vtkAbstractArray*>{ time, frame, averageError, maxError, neighbors,
      iterations, milliseconds, substeps, minTimeStep, maxTimeStep, maxSpeed, kinetic, particles,
      backend })
  {
    table->AddColumn(column);
  }
  if (loadImbalance)
  {
    table->AddColumn(imbalance);
  }
  AddLoadColumns(rows, table);
  AddBodyColumns(rows, table);
  return table;
}

//------------------------------------------------------------------------------
void vtkPBFOutput::AppendMesh(const pbf::SurfaceMesh& more, pbf::SurfaceMesh& mesh)
{
  const auto first = static_cast<std::uint32_t>(mesh.points.size());
  auto append = [](auto& to, const auto& from) { to.insert(to.end(), from.begin(), from.end()); };
  append(mesh.points, more.points);
  append(mesh.normals, more.normals);
  append(mesh.velocity, more.velocity);
  append(mesh.density, more.density);
  for (const auto& t : more.triangles)
  {
    mesh.triangles.push_back({ t[0] + first, t[1] + first, t[2] + first });
  }
  mesh.sampledBlocks += more.sampledBlocks;
  mesh.keptBlocks += more.keptBlocks;
  mesh.sampledNodes += more.sampledNodes;
  mesh.peakBytes = std::max(mesh.peakBytes, more.peakBytes);
}

//------------------------------------------------------------------------------
void vtkPBFOutput::AddLiquids(const std::vector<unsigned char>& liquid, vtkPolyData* surface)
{
  vtkNew<vtkUnsignedCharArray> array;
  array->SetName("liquid");
  array->SetNumberOfValues(static_cast<vtkIdType>(liquid.size()));
  std::copy(liquid.begin(), liquid.end(), array->GetPointer(0));
  surface->GetPointData()->AddArray(array);
}

//------------------------------------------------------------------------------
vtkSmartPointer<vtkPolyData> vtkPBFOutput::Surface(
  const pbf::SurfaceMesh& mesh, double milliseconds, const std::string& device)
{
  auto output = vtkSmartPointer<vtkPolyData>::New();
  const auto n = static_cast<vtkIdType>(mesh.points.size());
  auto vectors = [n](const char* name, const std::vector<pbf::Vec3<float>>& values) {
    auto array = vtkSmartPointer<vtkFloatArray>::New();
    array->SetName(name);
    array->SetNumberOfComponents(3);
    array->SetNumberOfTuples(values.empty() ? 0 : n);
    std::copy_n(&values.data()->x, 3 * values.size(), array->GetPointer(0));
    return array;
  };
  vtkNew<vtkPoints> points;
  points->SetData(vectors("Points", mesh.points));
  output->SetPoints(points);
  // The triangles as offsets 0, 3, 6, ... and the connectivity, without a cell at a time.
  const auto triangles = static_cast<vtkIdType>(mesh.triangles.size());
  vtkNew<vtkTypeInt64Array> offsets, connectivity;
  offsets->SetNumberOfValues(triangles + 1);
  connectivity->SetNumberOfValues(3 * triangles);
  for (vtkIdType t = 0; t <= triangles; ++t)
  {
    offsets->SetValue(t, 3 * t);
  }
  for (vtkIdType t = 0; t < triangles; ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      connectivity->SetValue(3 * t + k, mesh.triangles[static_cast<std::size_t>(t)][k]);
    }
  }
  vtkNew<vtkCellArray> polys;
  polys->SetData(offsets, connectivity);
  output->SetPolys(polys);
  vtkPointData* pd = output->GetPointData();
  pd->SetNormals(vectors("Normals", mesh.normals));
  if (!mesh.velocity.empty())
  {
    pd->SetVectors(vectors("velocity", mesh.velocity));
  }
  if (!mesh.density.empty())
  {
    auto density = vtkSmartPointer<vtkFloatArray>::New();
    density->SetName("density");
    density->SetNumberOfValues(n);
    std::copy(mesh.density.begin(), mesh.density.end(), density->GetPointer(0));
    pd->SetScalars(density);
  }
  vtkFieldData* fd = output->GetFieldData();
  AddInteger(fd, "SurfaceTriangles", triangles);
  AddValue(fd, "SurfaceMilliseconds", milliseconds);
  AddInteger(fd, "SurfaceBytes", static_cast<vtkIdType>(mesh.peakBytes));
  AddText(fd, "SurfaceDevice", device);
  return output;
}

//------------------------------------------------------------------------------
vtkSmartPointer<vtkPolyData> vtkPBFOutput::DomainOutline(const pbf::Box& box,
  const pbf::Scene& scene, const std::vector<pbf::SolidPose>& poses, double spacing)
{
  vtkNew<vtkAppendPolyData> all;
  // Each piece with a point array `Solid`: the index of the solid it draws, -1 for the outline.
  const auto tagged = [&all](vtkAlgorithm* piece, int solid) {
    piece->Update();
    vtkNew<vtkPolyData> copy;
    copy->ShallowCopy(piece->GetOutputDataObject(0));
    vtkNew<vtkIntArray> index;
    index->SetName("Solid");
    index->SetNumberOfTuples(copy->GetNumberOfPoints());
    index->FillValue(solid);
    copy->GetPointData()->AddArray(index);
    all->AddInputData(copy);
  };
  vtkNew<vtkOutlineSource> outline;
  outline->SetBounds(box.min.x, box.max.x, box.min.y, box.max.y, box.min.z, box.max.z);
  tagged(outline, -1);
  for (std::size_t k = 0; k < scene.solids.size(); ++k)
  {
    const pbf::SolidRegion& solid = scene.solids[k];
    vtkNew<vtkAppendPolyData> shape;
    if (solid.kind == pbf::SolidRegion::Kind::Box)
    {
      vtkNew<vtkTessellatedBoxSource> cube;
      cube->SetBounds(solid.box.min.x, solid.box.max.x, solid.box.min.y, solid.box.max.y,
        solid.box.min.z, solid.box.max.z);
      // The longest edge of the part within the domain, cut every spacing or so (at most 100
      // times: a floor slab far wider than the tank stays light).
      const auto within = [](double lo, double hi, double domainLo, double domainHi) {
        return std::min(hi, domainHi) - std::max(lo, domainLo);
      };
      const double longest =
        std::max({ within(solid.box.min.x, solid.box.max.x, box.min.x, box.max.x),
          within(solid.box.min.y, solid.box.max.y, box.min.y, box.max.y),
          within(solid.box.min.z, solid.box.max.z, box.min.z, box.max.z), 0.0 });
      const double cuts = spacing > 0 ? std::ceil(longest / spacing) : 1.0;
      cube->SetLevel(static_cast<int>(std::min(std::max(cuts - 1.0, 0.0), 99.0)));
      cube->QuadsOn();
      shape->AddInputConnection(cube->GetOutputPort());
    }
    else if (solid.kind == pbf::SolidRegion::Kind::Sphere)
    {
      vtkNew<vtkSphereSource> sphere;
      sphere->SetCenter(solid.center.x, solid.center.y, solid.center.z);
      sphere->SetRadius(solid.radius);
      sphere->SetThetaResolution(32);
      sphere->SetPhiResolution(32);
      shape->AddInputConnection(sphere->GetOutputPort());
    }
    else if (!solid.mesh.triangles.empty())
    {
      // A mesh file's or the Obstacles port's surface.
      vtkNew<vtkPoints> points;
      for (const pbf::Vec3d& p : solid.mesh.points)
      {
        points->InsertNextPoint(p.x, p.y, p.z);
      }
      vtkNew<vtkCellArray> triangles;
      for (const auto& t : solid.mesh.triangles)
      {
        const vtkIdType ids[3] = { t[0], t[1], t[2] };
        triangles->InsertNextCell(3, ids);
      }
      vtkNew<vtkPolyData> mesh;
      mesh->SetPoints(points);
      mesh->SetPolys(triangles);
      shape->AddInputData(mesh);
    }
    if (shape->GetNumberOfInputConnections(0) == 0)
    {
      continue;
    }
    // Where the solid stands at the frame: a point x of its own frame is at rotation x +
    // translation (SolidPose).
    vtkNew<vtkTransformPolyDataFilter> placed;
    placed->SetInputConnection(shape->GetOutputPort());
    vtkNew<vtkTransform> transform;
    if (k < poses.size())
    {
      const pbf::SolidPose& pose = poses[k];
      const auto& r = pose.rotation;
      const double matrix[16] = { r[0], r[1], r[2], pose.translation.x, r[3], r[4], r[5],
        pose.translation.y, r[6], r[7], r[8], pose.translation.z, 0, 0, 0, 1 };
      transform->SetMatrix(matrix);
    }
    placed->SetTransform(transform);
    tagged(placed, static_cast<int>(k));
  }

  all->Update();
  vtkSmartPointer<vtkPolyData> domain = all->GetOutput();
  AddText(domain->GetFieldData(), "Scene", scene.name);
  return domain;
}
