/**
 * @class   pqPBFApplyCamera
 * @brief   frames the whole tank after the first Apply of a Position Based Fluids source
 *
 * ParaView's Apply (pqApplyBehavior::showData) shows the output ports one by one and resets the
 * camera while the view holds a single visible dataset: that is port 0, the particles of frame 0,
 * a column in one corner of the tank. The Domain output (port 2, the tank and the obstacles)
 * comes next and no longer resets anything, so the surge runs out of the view on Play.
 *
 * This GUI component watches each vtkPBFSimulation proxy from its creation: when its first Apply
 * completes (the button, the keyboard or auto-apply: all end in the proxy leaving the
 * UNINITIALIZED state, after its representations exist), every render view that shows it and
 * nothing else is fitted to the union of the Domain and the particle bounds, its direction kept
 * (a new view looks at the tank's front face, gravity pointing down the screen). Views that
 * already showed other data, and proxies loaded from a state file, keep their cameras, as
 * ParaView's own Apply does.
 */
#ifndef pqPBFApplyCamera_h
#define pqPBFApplyCamera_h

#include <QObject>
#include <QPointer>
#include <QSet>

class pqPipelineSource;
class pqServerManagerModelItem;

class pqPBFApplyCamera : public QObject
{
  Q_OBJECT
  typedef QObject Superclass;

public:
  pqPBFApplyCamera(QObject* parent = nullptr);
  ~pqPBFApplyCamera() override;

  void startup();
  void shutdown();

private Q_SLOTS:
  void onSourceAdded(pqPipelineSource* source);
  void onModifiedStateChanged(pqServerManagerModelItem* item);

private:
  Q_DISABLE_COPY(pqPBFApplyCamera)

  void FrameDomain(pqPipelineSource* source);

  // Sources created but not applied yet.
  QSet<pqServerManagerModelItem*> Pending;
};

#endif
