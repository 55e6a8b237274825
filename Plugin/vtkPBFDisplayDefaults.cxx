#include "vtkPBFDisplayDefaults.h"

#include "vtkCommand.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkSMPVRepresentationProxy.h"
#include "vtkSMPropertyHelper.h"
#include "vtkSMProxy.h"
#include "vtkSMProxyManager.h"
#include "vtkSMSessionProxyManager.h"
#include "vtkSMTransferFunctionManager.h"
#include "vtkSmartPointer.h"
#include "vtkWeakPointer.h"

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

namespace
{
// The scene a display last showed (Preset and SceneFile): another scene starts from rest with
// other speeds, so its color map starts again from its data instead of keeping the old range.
std::string SceneOf(vtkSMProxy* producer)
{
  const char* file = vtkSMPropertyHelper(producer, "SceneFile").GetAsString();
  return std::to_string(vtkSMPropertyHelper(producer, "Preset").GetAsInt()) + "|" +
    (file ? file : "");
}

bool IsSimulation(vtkSMProxy* producer)
{
  return producer && producer->GetVTKClassName() &&
    std::strcmp(producer->GetVTKClassName(), "vtkPBFSimulation") == 0;
}

// The columns of the Diagnostics table, in the filter's order; only the density errors are
// plotted at first (the others are on other scales, one click away in the series list).
const char* const DiagnosticsColumns[] = { "AverageDensityError", "MaxDensityError",
  "AverageNeighbors", "SolverIterations", "MillisecondsPerStep", "Substeps", "MinTimeStep",
  "MaxTimeStep", "MaxSpeed", "KineticEnergy", "Frame", "Particles" };
} // namespace

struct vtkPBFDisplayDefaults::vtkInternals
{
  // A particle display and what this class last gave it: a display whose radius still equals
  // FollowedRadius was not changed by the user, so it follows the spacing.
  struct Followed
  {
    vtkWeakPointer<vtkSMProxy> Display;
    vtkWeakPointer<vtkSMProxy> Producer;
    double FollowedRadius = 0;
    std::string Scene;
  };
  std::vector<Followed> Displays;
  // Everything observed, with the observer's tag, so that the destructor can detach from what
  // still exists.
  template <class T>
  struct Watched
  {
    vtkWeakPointer<T> Object;
    unsigned long Tag;
  };
  std::vector<Watched<vtkSMSessionProxyManager>> Sessions;
  std::vector<Watched<vtkSMProxy>> Producers;
  Watched<vtkSMProxyManager> Manager{ nullptr, 0 };

  template <class T>
  static void Detach(std::vector<Watched<T>>& watched)
  {
    for (auto& w : watched)
    {
      if (w.Object)
      {
        w.Object->RemoveObserver(w.Tag);
      }
    }
    watched.clear();
  }

  template <class T>
  static bool Has(std::vector<Watched<T>>& watched, T* object)
  {
    watched.erase(std::remove_if(watched.begin(), watched.end(),
                    [](const Watched<T>& w) { return !w.Object; }),
      watched.end());
    return std::any_of(
      watched.begin(), watched.end(), [object](const Watched<T>& w) { return w.Object == object; });
  }

  void Prune()
  {
    Displays.erase(std::remove_if(Displays.begin(), Displays.end(),
                     [](const Followed& f) { return !f.Display || !f.Producer; }),
      Displays.end());
  }
};

vtkStandardNewMacro(vtkPBFDisplayDefaults);

//------------------------------------------------------------------------------
vtkPBFDisplayDefaults::vtkPBFDisplayDefaults()
  : Internals(new vtkInternals)
{
}

//------------------------------------------------------------------------------
vtkPBFDisplayDefaults::~vtkPBFDisplayDefaults()
{
  // Whatever still exists must not call back into a deleted object.
  vtkInternals::Detach(this->Internals->Sessions);
  vtkInternals::Detach(this->Internals->Producers);
  if (this->Internals->Manager.Object)
  {
    this->Internals->Manager.Object->RemoveObserver(this->Internals->Manager.Tag);
  }
}

//------------------------------------------------------------------------------
void vtkPBFDisplayDefaults::Install()
{
  // One per process, for the process's life: the plugin is loaded once and never unloaded.
  static vtkSmartPointer<vtkPBFDisplayDefaults> instance;
  if (instance || !vtkSMProxyManager::IsInitialized())
  {
    return; // loaded again, or in a process without a server manager (nothing is shown there)
  }
  instance = vtkSmartPointer<vtkPBFDisplayDefaults>::New();
  vtkSMProxyManager* manager = vtkSMProxyManager::GetProxyManager();
  instance->Internals->Manager = { manager,
    manager->AddObserver(vtkSMProxyManager::ActiveSessionChanged, instance.Get(),
      &vtkPBFDisplayDefaults::OnActiveSessionChanged) };
  instance->OnActiveSessionChanged(manager, vtkSMProxyManager::ActiveSessionChanged, nullptr);
}

//------------------------------------------------------------------------------
void vtkPBFDisplayDefaults::OnActiveSessionChanged(vtkObject*, unsigned long, void*)
{
  vtkSMProxyManager* manager = this->Internals->Manager.Object;
  vtkSMSessionProxyManager* session = manager ? manager->GetActiveSessionProxyManager() : nullptr;
  if (!session || vtkInternals::Has(this->Internals->Sessions, session))
  {
    return;
  }
  this->Internals->Sessions.push_back({ session,
    session->AddObserver(vtkCommand::RegisterEvent, this, &vtkPBFDisplayDefaults::OnRegistered) });
}

//------------------------------------------------------------------------------
void vtkPBFDisplayDefaults::OnRegistered(vtkObject* caller, unsigned long, void* callData)
{
  auto* info = static_cast<vtkSMProxyManager::RegisteredProxyInformation*>(callData);
  if (info && info->Type == vtkSMProxyManager::RegisteredProxyInformation::PROXY && info->Proxy &&
    info->GroupName && std::strcmp(info->GroupName, "representations") == 0)
  {
    this->Adopt(info->Proxy, vtkSMSessionProxyManager::SafeDownCast(caller));
  }
}

//------------------------------------------------------------------------------
void vtkPBFDisplayDefaults::Adopt(vtkSMProxy* display, vtkSMSessionProxyManager* proxyManager)
{
  if (!display || !display->GetProperty("Input"))
  {
    return;
  }
  vtkSMPropertyHelper input(display, "Input", /*quiet=*/true);
  vtkSMProxy* producer = input.GetAsProxy();
  if (!IsSimulation(producer))
  {
    return;
  }
  // A state file gives its displays their properties: they are followed, not reset.
  const bool fromState = proxyManager && proxyManager->GetInLoadXMLState();

  if (input.GetOutputPort() == 1 && display->GetProperty("SeriesVisibility"))
  {
    if (!fromState)
    {
      vtkSMPropertyHelper visibility(display, "SeriesVisibility");
      unsigned int element = 0;
      for (const char* column : DiagnosticsColumns)
      {
        const bool shown = std::strcmp(column, "AverageDensityError") == 0 ||
          std::strcmp(column, "MaxDensityError") == 0;
        visibility.Set(element++, column);
        visibility.Set(element++, shown ? "1" : "0");
      }
      display->UpdateVTKObjects();
    }
    return;
  }
  // The particles (port 0) in a view that draws Point Gaussians; the Domain outline (port 2)
  // keeps the representation's defaults.
  if (input.GetOutputPort() != 0 || !display->GetProperty("GaussianRadius"))
  {
    return;
  }
  const double spacing = vtkSMPropertyHelper(producer, "ParticleSpacing").GetAsDouble();
  if (!fromState)
  {
    vtkSMPropertyHelper(display, "GaussianRadius").Set(0.5 * spacing);
    display->UpdateVTKObjects();
    // The color map is the session's one for arrays named "velocity", the one Show picks.
    vtkNew<vtkSMTransferFunctionManager> colorMaps;
    if (vtkSMProxy* colors = colorMaps->GetColorTransferFunction(
          "velocity", proxyManager ? proxyManager : display->GetSessionProxyManager()))
    {
      vtkSMPropertyHelper(colors, "AutomaticRescaleRangeMode")
        .Set(vtkSMTransferFunctionManager::GROW_ON_APPLY_AND_TIMESTEP);
      colors->UpdateVTKObjects();
    }
  }
  vtkInternals::Followed followed;
  followed.Display = display;
  followed.Producer = producer;
  followed.FollowedRadius = 0.5 * spacing;
  followed.Scene = SceneOf(producer);
  this->Internals->Prune();
  this->Internals->Displays.push_back(followed);
  if (!vtkInternals::Has(this->Internals->Producers, producer))
  {
    this->Internals->Producers.push_back({ producer,
      producer->AddObserver(
        vtkCommand::UpdateDataEvent, this, &vtkPBFDisplayDefaults::OnDataUpdated) });
  }
}

//------------------------------------------------------------------------------
void vtkPBFDisplayDefaults::OnDataUpdated(vtkObject* caller, unsigned long, void*)
{
  vtkSMProxy* producer = vtkSMProxy::SafeDownCast(caller);
  this->Internals->Prune();
  for (vtkInternals::Followed& followed : this->Internals->Displays)
  {
    if (followed.Producer != producer)
    {
      continue;
    }
    vtkSMProxy* display = followed.Display;
    // The spacing changed (the data is then computed again): the spheres touch again, unless the
    // user has set a radius of their own.
    const double radius = vtkSMPropertyHelper(display, "GaussianRadius").GetAsDouble();
    const double wanted = 0.5 * vtkSMPropertyHelper(producer, "ParticleSpacing").GetAsDouble();
    if (radius == followed.FollowedRadius && radius != wanted)
    {
      vtkSMPropertyHelper(display, "GaussianRadius").Set(wanted);
      display->UpdateVTKObjects();
      followed.FollowedRadius = wanted;
    }
    const std::string scene = SceneOf(producer);
    if (scene != followed.Scene)
    {
      followed.Scene = scene;
      vtkSMPVRepresentationProxy::RescaleTransferFunctionToDataRange(
        display, /*extend=*/false, /*force=*/true);
    }
  }
}

//------------------------------------------------------------------------------
void vtkPBFDisplayDefaults::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Displays: " << this->Internals->Displays.size() << "\n";
  os << indent << "Sessions: " << this->Internals->Sessions.size() << "\n";
}

//------------------------------------------------------------------------------
void vtkPBFDisplayDefaultsInstall()
{
  vtkPBFDisplayDefaults::Install();
}
