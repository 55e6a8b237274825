// The Surface output of vtkPBFSimulation (port 3): the frame's particles made into a closed
// triangle mesh, on the run's ranks, its GPU or the CPU, cached per frame and options.
#include "vtkPBFOutput.h"
#include "vtkPBFSimulationInternals.h"

#include "vtkDataArray.h"
#include "vtkInformation.h"
#include "vtkOutputWindow.h"
#include "vtkPointData.h"
#include "vtkPoints.h"

#include "Parameters.h"
#include "Stepper.h"
#include "SurfaceShare.h"
#include "Distributed/SubdomainStepper.h"
#ifdef PBF_WITH_CUDA
#include "Cuda/CudaBackend.h"
#include "Cuda/CudaSurface.h"
#endif

#include <chrono>
#include <sstream>
#include <string>
#include <vector>

//------------------------------------------------------------------------------
void vtkPBFSimulationInternals::DeliverSurface(
  const pbf::SurfaceOptions& options, vtkPolyData* particles, vtkPolyData* surface)
{
  options.validate();
  // The run's own parameters: the domain (which anchors the surface's grid) is the scene's.
  const pbf::Simulation* live = this->Playback.live();
  if (!this->Playback.hasKey() || !live)
  {
    surface->Initialize();
    return;
  }
  const pbf::Parameters& p = live->parameters();
  // A decomposed run: every rank its slab's share, the border particles exchanged (collective,
  // so every rank computes it every time: no rank may skip on a cache of its own).
  const auto* decomposed = this->Playback.key().ranks > 1 && this->Ranks
    ? dynamic_cast<const pbf::distributed::DecomposedStepper*>(&live->stepper())
    : nullptr;
  pbf::SurfaceOptions used = options;
  if (decomposed && used.smoothing > 0)
  {
    // Smoothing moves a vertex by its neighbours, which a border vertex has on two ranks.
    used.smoothing = 0;
    if (!this->SmoothingDecomposedSaid)
    {
      this->SmoothingDecomposedSaid = true;
      vtkOutputWindowDisplayWarningText("SurfaceSmoothing is not applied in a decomposed run: "
                                        "it would open cracks at the slab borders.\n");
    }
  }
  std::ostringstream of;
  of.precision(17);
  of << particles->GetMTime() << " " << options.resolution << " " << options.isoValue << " "
     << options.smoothing << " " << options.anisotropic << " " << p.particleSpacing << " " << p.smoothingRatio << " "
     << p.restDensity;
  if (decomposed || of.str() != this->LastSurfaceOf)
  {
    const auto start = std::chrono::steady_clock::now();
    vtkDataArray* x = particles->GetPoints() ? particles->GetPoints()->GetData() : nullptr;
    vtkDataArray* v = particles->GetPointData()->GetArray("velocity");
    vtkDataArray* rho = particles->GetPointData()->GetArray("density");
    const std::size_t n = x ? static_cast<std::size_t>(x->GetNumberOfTuples()) : 0;
    pbf::SurfaceMesh mesh;
    std::string device;
    // The obstacles where they stand at the frame's time clip the surface.
    vtkInformation* info = particles->GetInformation();
    const double time =
      info->Has(vtkDataObject::DATA_TIME_STEP()) ? info->Get(vtkDataObject::DATA_TIME_STEP()) : 0.0;
    const pbf::SurfaceSolids solids = live->surfaceSolids(time);
    // Several liquids: one closed surface per liquid, each made from its own particles as a
    // fluid of its rest density (their point array "liquid" says which).
    vtkDataArray* liquidArray = particles->GetPointData()->GetArray("liquid");
    const int liquids = !p.liquids.empty() && liquidArray ? p.liquidCount() : 0;
    std::vector<unsigned char> meshLiquid;
    const int type = x ? x->GetDataType() : VTK_FLOAT;
    const bool same = (!v || v->GetDataType() == type) && (!rho || rho->GetDataType() == type);
    if (n > 0 && (!same || (type != VTK_FLOAT && type != VTK_DOUBLE)))
    {
      throw pbf::InvalidInput("Surface: the particles' arrays are not all float or all double");
    }
    if (type == VTK_DOUBLE)
    {
      this->ExtractMesh<double>(
        particles, p, used, solids, decomposed, liquids, mesh, meshLiquid, device);
    }
    else
    {
      this->ExtractMesh<float>(
        particles, p, used, solids, decomposed, liquids, mesh, meshLiquid, device);
    }
    const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    this->LastSurface = vtkPBFOutput::Surface(mesh, ms, device);
    if (liquids > 0)
    {
      vtkPBFOutput::AddLiquids(meshLiquid, this->LastSurface);
    }
    this->LastSurfaceOf = of.str();
  }
  surface->ShallowCopy(this->LastSurface);
}

//------------------------------------------------------------------------------
template <class Real>
void vtkPBFSimulationInternals::ExtractMesh(vtkPolyData* particles, const pbf::Parameters& p,
  const pbf::SurfaceOptions& used, const pbf::SurfaceSolids& solids,
  const pbf::distributed::DecomposedStepper* decomposed, int liquids, pbf::SurfaceMesh& mesh,
  std::vector<unsigned char>& meshLiquid, std::string& device)
{
  const pbf::Simulation* live = this->Playback.live();
  vtkDataArray* x = particles->GetPoints() ? particles->GetPoints()->GetData() : nullptr;
  vtkDataArray* v = particles->GetPointData()->GetArray("velocity");
  vtkDataArray* rho = particles->GetPointData()->GetArray("density");
  vtkDataArray* liquidArray = particles->GetPointData()->GetArray("liquid");
  const std::size_t n = x ? static_cast<std::size_t>(x->GetNumberOfTuples()) : 0;
  // The frame's own arrays, in the run's precision, read in place.
  auto pointer = [](vtkDataArray* a) { return a ? static_cast<Real*>(a->GetVoidPointer(0)) : nullptr; };
  auto extractOf = [&](const pbf::Vec3<Real>* px, const pbf::Vec3<Real>* pv, const Real* prho,
                     std::size_t count, const pbf::Parameters& of) {
    pbf::SurfaceMesh made;
    if (decomposed)
    {
      made = pbf::extractSurfaceShare<Real>(
        *this->Ranks, decomposed->slabs(), px, pv, prho, count, of, used, true, solids);
    }
    else if (!this->ExtractOnGpu(
               live->stepper(), px, pv, prho, count, of, used, solids, made, device))
    {
      made = pbf::extractSurface<Real>(px, pv, prho, count, of, used, true, {}, solids);
      device = "CPU";
    }
    return made;
  };
  const auto* px = reinterpret_cast<const pbf::Vec3<Real>*>(pointer(x));
  const auto* pv = reinterpret_cast<const pbf::Vec3<Real>*>(pointer(v));
  if (liquids == 0)
  {
    mesh = extractOf(px, pv, pointer(rho), n, p);
    return;
  }
  const auto* liquid = static_cast<const unsigned char*>(liquidArray->GetVoidPointer(0));
  for (int l = 0; l < liquids; ++l)
  {
    std::vector<pbf::Vec3<Real>> lx, lv;
    std::vector<Real> lrho;
    for (std::size_t i = 0; i < n; ++i)
    {
      if (liquid[i] == l)
      {
        lx.push_back(px[i]);
        lv.push_back(pv ? pv[i] : pbf::Vec3<Real>{});
        lrho.push_back(pointer(rho) ? pointer(rho)[i] : Real(0));
      }
    }
    pbf::Parameters own = p;
    own.restDensity = p.liquidRestDensity(l);
    own.liquids.clear();
    const pbf::SurfaceMesh part = extractOf(lx.data(), pv ? lv.data() : nullptr,
      pointer(rho) ? lrho.data() : nullptr, lx.size(), own);
    vtkPBFOutput::AppendMesh(part, mesh);
    meshLiquid.resize(mesh.points.size(), static_cast<unsigned char>(l));
  }
}

//------------------------------------------------------------------------------
template <class Real>
bool vtkPBFSimulationInternals::ExtractOnGpu(const pbf::Stepper& stepper,
  const pbf::Vec3<Real>* x, const pbf::Vec3<Real>* v, const Real* rho, std::size_t n,
  const pbf::Parameters& p, const pbf::SurfaceOptions& options, const pbf::SurfaceSolids& solids,
  pbf::SurfaceMesh& mesh, std::string& device)
{
#ifdef PBF_WITH_CUDA
  const auto* gpu = dynamic_cast<const pbf::cuda::CudaStepperInterface*>(&stepper);
  if (!gpu)
  {
    return false;
  }
  try
  {
    if (!this->GpuSurface)
    {
      this->GpuSurface = std::make_shared<pbf::cuda::SurfaceExtractor>();
    }
    // The frame's arrays (the frame asked may be a cached one, not the stepper's present state).
    auto* extractor = static_cast<pbf::cuda::SurfaceExtractor*>(this->GpuSurface.get());
    mesh = extractor->extract<Real>(x, v, rho, n, p, options, solids);
    device = gpu->diagnostics().device;
    return true;
  }
  catch (const pbf::InvalidInput&)
  {
    throw; // the input's fault, on any device: the filter reports it
  }
  catch (const std::exception& error)
  {
    // The GPU could not make it (a device fault, too little memory of another kind): the CPU can.
    this->GpuSurface.reset();
    if (!this->GpuSurfaceFailedSaid)
    {
      this->GpuSurfaceFailedSaid = true;
      vtkOutputWindowDisplayWarningText(
        (std::string("The surface is made on the CPU: the GPU failed (") + error.what() + ").\n").c_str());
    }
    return false;
  }
#else
  (void)stepper;
  (void)x;
  (void)v;
  (void)rho;
  (void)n;
  (void)p;
  (void)options;
  (void)solids;
  (void)mesh;
  (void)device;
  return false;
#endif
}

