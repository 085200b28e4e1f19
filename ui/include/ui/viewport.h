// The 3D viewport: draws the RenderScene (OpenGL 3.3 core, shaders from resources/shaders)
// through an OrbitCamera, and turns mouse input into camera moves, selection and pin drags.
//
// Mouse (as Blender): middle drag orbits, Shift+middle pans, Ctrl+middle or the wheel zooms;
// Alt+left orbits too, for laptops. Left click selects a body; left drag on a pin handle moves
// the pin's target in the plane facing the camera (one merged undo command per drag). With the
// pin tool on, a left click on a body adds a pin at the clicked point at the current time; with
// the pose tool on, a left drag on a body turns its joint (an unkeyed pose, keyed with K).
#pragma once

#include <QOpenGLBuffer>
#include <QOpenGLFunctions_3_3_Core>
#include <QOpenGLShaderProgram>
#include <QOpenGLVertexArrayObject>
#include <QOpenGLWidget>
#include <array>
#include <memory>
#include <optional>
#include <vector>

#include "dynamics/inverse_kinematics.h"
#include "ui/camera.h"
#include "ui/document.h"
#include "ui/render_scene.h"

namespace spacetime::ui {

// Makes OpenGL 3.3 core (with a depth buffer and `samples` MSAA samples) the default for every
// GL widget. Call before the QApplication exists.
void useOpenGL33CoreByDefault(int samples = 0);

class Viewport : public QOpenGLWidget, protected QOpenGLFunctions_3_3_Core {
  Q_OBJECT
 public:
  explicit Viewport(Document* doc, QWidget* parent = nullptr);
  ~Viewport() override;

  OrbitCamera& camera() { return camera_; }
  RenderOptions& options() { return options_; }
  const RenderScene& renderScene();  // rebuilt if the document changed

  void frameAll();
  void setPinTool(bool on) { pinTool_ = on; }
  // The next click on the contact term's body adds the clicked point (in the body's frame) to
  // its points, as one undo step; a click elsewhere only selects.
  void setContactPointTool(const std::string& term) { contactPointTerm_ = term; }
  const std::string& contactPointTool() const { return contactPointTerm_; }
  bool pinTool() const { return pinTool_; }
  // The pose tool: a left drag on a body turns its joint around the ring drawn at the joint (the
  // angle the mouse sweeps around the joint on screen, within the joint's limits); Shift+drag
  // pulls the grabbed point and the joints up to the root follow (inverse kinematics). Either
  // leaves an unkeyed pose that K keys.
  void setPoseTool(bool on) {
    poseTool_ = on;
    invalidate();
  }
  bool poseTool() const { return poseTool_; }
  // Follow the character: the camera's target keeps its offset from the selected (or first)
  // character's centre of mass as the time changes, so a long jump stays in view.
  void setFollow(bool on);
  bool follow() const { return follow_; }
  // Draws one frame into the current framebuffer and waits for the GPU (for the benchmark).
  double renderFrameAndFinish();
  // The view as it is now, rendered offscreen at `size` pixels (4x multisampled): image exports
  // at a resolution other than the window's.
  QImage renderImage(const QSize& size);
  double lastFrameMilliseconds() const { return lastFrameMs_; }

  // The pixel position of a world point (for tests driving the mouse).
  QPointF toPixel(const glm::vec3& p) const;

 public slots:
  void invalidate();  // the document changed: rebuild the RenderScene and repaint

 signals:
  void pinToolUsed();
  // The click that ends the contact-point tool: added says whether the contact got its point
  // (false: the click was off the contact's body, and nothing changed).
  void contactPointToolDone(const QString& term, bool added);

 protected:
  void initializeGL() override;
  void paintGL() override;
  void mousePressEvent(QMouseEvent* e) override;
  void mouseMoveEvent(QMouseEvent* e) override;
  void mouseReleaseEvent(QMouseEvent* e) override;
  void wheelEvent(QWheelEvent* e) override;

 private:
  struct GpuMesh {
    QOpenGLVertexArrayObject vao;
    QOpenGLBuffer vbo{QOpenGLBuffer::VertexBuffer};
    int count = 0;
  };
  void uploadMesh(Mesh mesh, const std::vector<float>& vertices);
  void drawSolid(const Solid& s);  // with the solid shader bound
  void drawLines(const std::vector<float>& vertices, GLenum mode, const glm::mat4& viewProjection);
  void clickAt(const QPointF& pos);
  // false: no body there whose joint turns (ik: no joints between it and the root).
  bool startPose(const QPointF& pos, bool ik);
  void dragIk(const QPointF& pos);
  // Where the mouse's ray meets the plane of the current drag (dragPlanePoint_, dragPlaneNormal_).
  std::optional<glm::vec3> onDragPlane(const QPointF& pos) const;
  void dragPose(const QPointF& pos);
  double screenAngle(const PoseJoint& joint, const QPointF& pos) const;
  int handleAt(const QPointF& pos);

  Document* doc_;
  OrbitCamera camera_;
  RenderOptions options_;
  RenderScene scene_;
  bool dirty_ = true;
  bool pinTool_ = false;
  bool poseTool_ = false;
  std::string contactPointTerm_;  // the contact the next click adds a point to (empty: none)
  bool addContactPoint(const Solid& s, const glm::vec3& hit);  // false: not the contact's body
  bool follow_ = false;
  glm::vec3 followOffset_{0.0f};
  std::optional<glm::vec3> followedCentre() const;  // the followed character's centre of mass now
  bool framedOnce_ = false;

  std::unique_ptr<QOpenGLShaderProgram> solidShader_, lineShader_;
  std::array<std::unique_ptr<GpuMesh>, 4> meshes_;
  QOpenGLVertexArrayObject lineVao_;
  QOpenGLBuffer lineVbo_{QOpenGLBuffer::VertexBuffer};
  double lastFrameMs_ = 0;
  QSize renderSize_;  // the offscreen image's size while renderImage draws; invalid otherwise

  // Mouse state.
  enum class Drag { None, Orbit, Pan, Zoom, Handle, Click, Pose, PoseIk } drag_ = Drag::None;
  struct IkDrag {  // the grabbed point moves in the drag plane
    int character = -1, body = -1;
    Eigen::Vector3d local = Eigen::Vector3d::Zero();  // the grabbed point, in the body's frame
    std::vector<int> dofs;         // the dofs that move: the chain up to the root, or plantedIkDofs
    std::vector<IkPoint> planted;  // contact points on the ground now, held where they are
  } ik_;
  struct PoseDrag {
    int character = -1;
    PoseJoint joint;        // the joint turned, as it was when the drag began
    Eigen::VectorXd start;  // the pose when the drag began
    double swept = 0, lastAngle = 0, sign = 1;
  } pose_;
  QPointF last_, pressPos_;
  std::string dragTerm_;
  int dragSerial_ = 0;
  // The undo merge id of the pin drag under way: its moves become one command.
  int dragMergeId() const { return kMergePinDrag + (dragSerial_ & 0xFFFFF); }
  // The plane facing the camera that a dragged pin handle or pulled body point moves in.
  glm::vec3 dragPlanePoint_{0.0f}, dragPlaneNormal_{0.0f, 0.0f, 1.0f};
};

}  // namespace spacetime::ui
