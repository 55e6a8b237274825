#include "pqPBFApplyCamera.h"

#include "pqApplicationCore.h"
#include "pqDataRepresentation.h"
#include "pqOutputPort.h"
#include "pqPipelineSource.h"
#include "pqRenderView.h"
#include "pqServerManagerModel.h"
#include "vtkBoundingBox.h"
#include "vtkPVDataInformation.h"
#include "vtkSMRenderViewProxy.h"
#include "vtkSMSourceProxy.h"

#include <cstring>

namespace
{
// The output that draws the tank and the obstacles (vtkPBFSimulation's port 2).
constexpr int DomainPort = 2;

bool IsSimulation(pqPipelineSource* source)
{
  vtkSMProxy* proxy = source ? source->getProxy() : nullptr;
  return proxy && proxy->GetVTKClassName() &&
    std::strcmp(proxy->GetVTKClassName(), "vtkPBFSimulation") == 0;
}
} // namespace

//-----------------------------------------------------------------------------
pqPBFApplyCamera::pqPBFApplyCamera(QObject* parentObject)
  : Superclass(parentObject)
{
}

//-----------------------------------------------------------------------------
pqPBFApplyCamera::~pqPBFApplyCamera() = default;

//-----------------------------------------------------------------------------
void pqPBFApplyCamera::startup()
{
  pqServerManagerModel* model = pqApplicationCore::instance()->getServerManagerModel();
  QObject::connect(
    model, &pqServerManagerModel::sourceAdded, this, &pqPBFApplyCamera::onSourceAdded);
  // Sources that exist already (the plugin loaded after they were made) are followed too.
  for (pqPipelineSource* source : model->findItems<pqPipelineSource*>())
  {
    this->onSourceAdded(source);
  }
}

//-----------------------------------------------------------------------------
void pqPBFApplyCamera::shutdown()
{
  this->Pending.clear();
}

//-----------------------------------------------------------------------------
void pqPBFApplyCamera::onSourceAdded(pqPipelineSource* source)
{
  if (!IsSimulation(source))
  {
    return;
  }
  // The object builder marks a new source UNINITIALIZED after this signal; one made otherwise
  // (a state file, Python) may be so already.
  if (source->modifiedState() == pqProxy::UNINITIALIZED)
  {
    this->Pending.insert(source);
  }
  QObject::connect(source, &pqProxy::modifiedStateChanged, this,
    &pqPBFApplyCamera::onModifiedStateChanged, Qt::UniqueConnection);
  QObject::connect(source, &QObject::destroyed, this,
    [this, source]() { this->Pending.remove(source); });
}

//-----------------------------------------------------------------------------
void pqPBFApplyCamera::onModifiedStateChanged(pqServerManagerModelItem* item)
{
  auto* source = qobject_cast<pqPipelineSource*>(item);
  if (!source)
  {
    return;
  }
  if (source->modifiedState() == pqProxy::UNINITIALIZED)
  {
    this->Pending.insert(source);
    return;
  }
  // pqApplyBehavior leaves UNINITIALIZED once the first Apply has shown every port; later
  // Applies (UNMODIFIED again after MODIFIED) keep the camera the user has by then.
  if (source->modifiedState() == pqProxy::UNMODIFIED && this->Pending.remove(source))
  {
    this->FrameDomain(source);
  }
}

//-----------------------------------------------------------------------------
void pqPBFApplyCamera::FrameDomain(pqPipelineSource* source)
{
  vtkBoundingBox box;
  for (int port : { 0, DomainPort })
  {
    pqOutputPort* output = source->getOutputPort(port);
    vtkPVDataInformation* info = output ? output->getDataInformation() : nullptr;
    if (info && info->GetNumberOfPoints() > 0)
    {
      box.AddBounds(info->GetBounds());
    }
  }
  if (!box.IsValid())
  {
    return; // the run failed: nothing to frame, the error is already in Output Messages
  }
  double bounds[6];
  box.GetBounds(bounds);
  for (pqView* view : source->getViews())
  {
    auto* renderView = qobject_cast<pqRenderView*>(view);
    if (!renderView)
    {
      continue;
    }
    // Only a view whose every visible dataset is this source's: another dataset shown there
    // means the user framed that view already.
    bool onlyThisSource = true;
    for (pqRepresentation* representation : renderView->getRepresentations())
    {
      auto* data = qobject_cast<pqDataRepresentation*>(representation);
      if (data && data->isVisible() && data->getInput() != source)
      {
        onlyThisSource = false;
      }
    }
    if (onlyThisSource)
    {
      renderView->getRenderViewProxy()->ResetCamera(bounds, /*closest=*/true);
      renderView->render();
    }
  }
}
