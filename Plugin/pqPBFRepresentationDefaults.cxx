#include "pqPBFRepresentationDefaults.h"

#include "pqApplicationCore.h"
#include "pqPipelineSource.h"
#include "pqRepresentation.h"
#include "pqServerManagerModel.h"
#include "vtkNew.h"
#include "vtkSMPropertyHelper.h"
#include "vtkSMPVRepresentationProxy.h"
#include "vtkSMProxy.h"
#include "vtkSMSessionProxyManager.h"
#include "vtkSMTransferFunctionManager.h"
#include "vtkWeakPointer.h"

#include <QPointer>
#include <QString>
#include <QVariant>

#include <cstring>

namespace
{
// The radius this class last gave a display, kept on the pqRepresentation: a display whose radius
// still equals it was not changed by the user, so it follows the spacing.
const char* const FollowedRadius = "pbfFollowedGaussianRadius";

// The scene last seen by a display (Preset and SceneFile): another scene starts from rest with
// other speeds, so the color map starts again from its data instead of keeping the old range.
const char* const FollowedScene = "pbfFollowedScene";

QString SceneOf(vtkSMProxy* producer)
{
  const char* file = vtkSMPropertyHelper(producer, "SceneFile").GetAsString();
  return QString::number(vtkSMPropertyHelper(producer, "Preset").GetAsInt()) + "|" +
    QString::fromUtf8(file ? file : "");
}

void FollowScene(pqRepresentation* representation, vtkSMProxy* producer)
{
  const QString scene = SceneOf(producer);
  const QVariant followed = representation->property(FollowedScene);
  representation->setProperty(FollowedScene, scene);
  if (followed.isValid() && followed.toString() != scene)
  {
    vtkSMPVRepresentationProxy::RescaleTransferFunctionToDataRange(
      representation->getProxy(), /*extend=*/false, /*force=*/true);
    representation->renderViewEventually();
  }
}

void FollowSpacing(pqRepresentation* representation, vtkSMProxy* producer)
{
  vtkSMProxy* display = representation->getProxy();
  const QVariant followed = representation->property(FollowedRadius);
  const double radius = vtkSMPropertyHelper(display, "GaussianRadius").GetAsDouble();
  const double wanted = 0.5 * vtkSMPropertyHelper(producer, "ParticleSpacing").GetAsDouble();
  if (!followed.isValid() || radius != followed.toDouble() || radius == wanted)
  {
    return;
  }
  vtkSMPropertyHelper(display, "GaussianRadius").Set(wanted);
  representation->setProperty(FollowedRadius, wanted);
  display->UpdateVTKObjects();
  representation->renderViewEventually();
}
} // namespace

//------------------------------------------------------------------------------
pqPBFRepresentationDefaults::pqPBFRepresentationDefaults(QObject* parent)
  : Superclass(parent)
{
}

//------------------------------------------------------------------------------
pqPBFRepresentationDefaults::~pqPBFRepresentationDefaults() = default;

//------------------------------------------------------------------------------
void pqPBFRepresentationDefaults::startup()
{
  pqServerManagerModel* model = pqApplicationCore::instance()->getServerManagerModel();
  QObject::connect(model, &pqServerManagerModel::representationAdded, this,
    &pqPBFRepresentationDefaults::onRepresentationAdded);
}

//------------------------------------------------------------------------------
void pqPBFRepresentationDefaults::shutdown()
{
  pqServerManagerModel* model = pqApplicationCore::instance()->getServerManagerModel();
  QObject::disconnect(model, nullptr, this, nullptr);
}

//------------------------------------------------------------------------------
void pqPBFRepresentationDefaults::onRepresentationAdded(pqRepresentation* representation)
{
  vtkSMProxy* display = representation ? representation->getProxy() : nullptr;
  if (!display || !display->GetProperty("Input"))
  {
    return;
  }
  vtkSMPropertyHelper input(display, "Input", /*quiet=*/true);
  vtkSMProxy* producer = input.GetAsProxy();
  if (!producer || !producer->GetVTKClassName() ||
    std::strcmp(producer->GetVTKClassName(), "vtkPBFSimulation") != 0)
  {
    return;
  }
  // The diagnostics (port 1) in a chart: against Time (ParaView's default X array when a column
  // has that name), the two density errors only, both in percent; the other columns are on
  // other scales and one click away in the series list.
  if (input.GetOutputPort() == 1 && display->GetProperty("SeriesVisibility"))
  {
    static const char* const columns[] = { "AverageDensityError", "MaxDensityError",
      "AverageNeighbors", "SolverIterations", "MillisecondsPerStep", "Substeps", "MinTimeStep",
      "MaxTimeStep", "MaxSpeed", "KineticEnergy", "Frame", "Particles" };
    vtkSMPropertyHelper visibility(display, "SeriesVisibility");
    unsigned int element = 0;
    for (const char* column : columns)
    {
      const bool shown = std::strcmp(column, "AverageDensityError") == 0 ||
        std::strcmp(column, "MaxDensityError") == 0;
      visibility.Set(element++, column);
      visibility.Set(element++, shown ? "1" : "0");
    }
    display->UpdateVTKObjects();
    return;
  }
  // Only data representations that can draw Point Gaussians (render views) have a radius.
  if (!display->GetProperty("GaussianRadius"))
  {
    return;
  }

  const double spacing = vtkSMPropertyHelper(producer, "ParticleSpacing").GetAsDouble();
  vtkSMPropertyHelper(display, "GaussianRadius").Set(0.5 * spacing);
  display->UpdateVTKObjects();
  // ... and whenever the spacing changes (the data is then computed again), unless the user has
  // set a radius of their own.
  representation->setProperty(FollowedRadius, 0.5 * spacing);
  representation->setProperty(FollowedScene, SceneOf(producer));
  pqServerManagerModel* model = pqApplicationCore::instance()->getServerManagerModel();
  if (auto* source = model->findItem<pqPipelineSource*>(producer))
  {
    QPointer<pqRepresentation> guard(representation);
    vtkWeakPointer<vtkSMProxy> weakProducer(producer);
    QObject::connect(source, QOverload<pqPipelineSource*>::of(&pqPipelineSource::dataUpdated),
      representation,
      [guard, weakProducer](pqPipelineSource*) {
        if (guard && weakProducer)
        {
          FollowSpacing(guard, weakProducer);
          FollowScene(guard, weakProducer);
        }
      });
  }

  // The color map is the session's one for arrays named "velocity", the one Show picks.
  vtkNew<vtkSMTransferFunctionManager> manager;
  if (vtkSMProxy* colors =
        manager->GetColorTransferFunction("velocity", display->GetSessionProxyManager()))
  {
    vtkSMPropertyHelper(colors, "AutomaticRescaleRangeMode")
      .Set(vtkSMTransferFunctionManager::GROW_ON_APPLY_AND_TIMESTEP);
    colors->UpdateVTKObjects();
  }
}
