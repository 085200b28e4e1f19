#include "ui/viewport.h"

#include <QOpenGLFramebufferObject>

#include <QElapsedTimer>
#include <QMouseEvent>
#include <QSurfaceFormat>
#include <QWheelEvent>
#include <cmath>
#include <glm/gtc/matrix_inverse.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "core/shape_mesh.h"
#include "dynamics/algorithms.h"
#include "dynamics/inverse_kinematics.h"

namespace spacetime::ui {

namespace {

using Vertices = std::vector<float>;  // interleaved position (3) and normal (3), triangles

// The shared unit mesh (core/shape_mesh.h) unrolled into the interleaved triangle list drawn
// with glDrawArrays.
Vertices unrolled(UnitShape shape) {
  const TriangleMesh mesh = unitShapeMesh(shape);
  Vertices v;
  v.reserve(mesh.indices.size() * 6);
  for (std::uint32_t i : mesh.indices) {
    const Eigen::Vector3f& p = mesh.positions[i];
    const Eigen::Vector3f& n = mesh.normals[i];
    v.insert(v.end(), {p.x(), p.y(), p.z(), n.x(), n.y(), n.z()});
  }
  return v;
}

void pushLine(std::vector<float>& v, const glm::vec3& p, const glm::vec4& c) {
  v.insert(v.end(), {p.x, p.y, p.z, c.r, c.g, c.b, c.a});
}

}  // namespace

void useOpenGL33CoreByDefault(int samples) {
  QSurfaceFormat format;
  format.setVersion(3, 3);
  format.setProfile(QSurfaceFormat::CoreProfile);
  format.setDepthBufferSize(24);
  format.setSamples(samples);
  QSurfaceFormat::setDefaultFormat(format);
}

Viewport::Viewport(Document* doc, QWidget* parent) : QOpenGLWidget(parent), doc_(doc) {
  setObjectName("viewport");
  setMinimumSize(320, 240);
  setFocusPolicy(Qt::StrongFocus);
  for (auto signal : {&Document::sceneChanged, &Document::motionChanged, &Document::selectionChanged, &Document::poseChanged})
    connect(doc_, signal, this, &Viewport::invalidate);
  connect(doc_, &Document::currentTimeChanged, this, &Viewport::invalidate);
  camera_.front();
}

Viewport::~Viewport() {
  makeCurrent();
  for (auto& m : meshes_) m.reset();
  lineVbo_.destroy();
  lineVao_.destroy();
  solidShader_.reset();
  lineShader_.reset();
  doneCurrent();
}

void Viewport::invalidate() {
  dirty_ = true;
  update();
}

const RenderScene& Viewport::renderScene() {
  if (dirty_) {
    options_.time = doc_->currentTime();
    options_.selectedCharacter = doc_->selectedCharacter();
    options_.selectedBody = doc_->selectedBody();
    options_.selectedTerm = doc_->selectedTerm();
    options_.poseGizmo = poseTool_;
    options_.posedCharacter = doc_->posed() ? doc_->posed()->character : -1;
    options_.posedQ = doc_->posed() ? doc_->posed()->q : Eigen::VectorXd();
    scene_ = buildRenderScene(doc_->scene(), doc_->models(), doc_->motion().get(), options_);
    dirty_ = false;
    if (!framedOnce_ && !scene_.solids.empty()) {
      framedOnce_ = true;
      camera_.frame(scene_.boundsMin, scene_.boundsMax);
    }
    if (follow_) {
      if (const std::optional<glm::vec3> com = followedCentre()) camera_.target = *com + followOffset_;
    }
  }
  return scene_;
}

std::optional<glm::vec3> Viewport::followedCentre() const {
  const int c = std::max(0, doc_->selectedCharacter());
  if (static_cast<size_t>(c) >= doc_->models().size() || doc_->models()[c].totalMass() <= 0) return std::nullopt;
  const Model<double>& model = doc_->models()[c];
  Data<double> d(model);
  forwardKinematics(model, d, doc_->posesNow()[c].data());
  return toGlm(centerOfMass(model, d));
}

void Viewport::setFollow(bool on) {
  follow_ = false;
  if (on) {
    // Keep the view where it is now relative to the character: the camera moves with it.
    const std::optional<glm::vec3> com = followedCentre();
    if (!com) return;
    followOffset_ = camera_.target - *com;
    follow_ = true;
  }
  invalidate();
}

void Viewport::frameAll() {
  const RenderScene& rs = renderScene();
  camera_.frame(rs.boundsMin, rs.boundsMax);
  if (follow_) setFollow(true);  // follow from the framed view
  update();
}

void Viewport::uploadMesh(Mesh mesh, const std::vector<float>& vertices) {
  auto m = std::make_unique<GpuMesh>();
  m->vao.create();
  m->vao.bind();
  m->vbo.create();
  m->vbo.bind();
  m->vbo.allocate(vertices.data(), static_cast<int>(vertices.size() * sizeof(float)));
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), reinterpret_cast<void*>(3 * sizeof(float)));
  m->count = static_cast<int>(vertices.size() / 6);
  m->vao.release();
  meshes_[static_cast<int>(mesh)] = std::move(m);
}

void Viewport::initializeGL() {
  initializeOpenGLFunctions();
  auto load = [](const char* vert, const char* frag) {
    auto p = std::make_unique<QOpenGLShaderProgram>();
    if (!p->addShaderFromSourceFile(QOpenGLShader::Vertex, vert) ||
        !p->addShaderFromSourceFile(QOpenGLShader::Fragment, frag) || !p->link())
      qWarning("viewport: shader %s/%s failed: %s", vert, frag, qPrintable(p->log()));
    return p;
  };
  solidShader_ = load(":/shaders/solid.vert", ":/shaders/solid.frag");
  lineShader_ = load(":/shaders/line.vert", ":/shaders/line.frag");
  uploadMesh(Mesh::Cube, unrolled(UnitShape::Cube));
  uploadMesh(Mesh::Sphere, unrolled(UnitShape::Sphere));
  uploadMesh(Mesh::Cylinder, unrolled(UnitShape::Cylinder));
  uploadMesh(Mesh::Cone, unrolled(UnitShape::Cone));
  lineVao_.create();
  lineVao_.bind();
  lineVbo_.create();
  lineVbo_.setUsagePattern(QOpenGLBuffer::StreamDraw);
  lineVbo_.bind();
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 7 * sizeof(float), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, 7 * sizeof(float), reinterpret_cast<void*>(3 * sizeof(float)));
  lineVao_.release();
}

void Viewport::drawSolid(const Solid& s) {
  solidShader_->setUniformValue("color", QVector4D(s.color.r, s.color.g, s.color.b, s.color.a));
  glUniformMatrix4fv(solidShader_->uniformLocation("model"), 1, GL_FALSE, glm::value_ptr(s.transform));
  const glm::mat3 normal = glm::inverseTranspose(glm::mat3(s.transform));
  glUniformMatrix3fv(solidShader_->uniformLocation("normalMatrix"), 1, GL_FALSE, glm::value_ptr(normal));
  GpuMesh& m = *meshes_[static_cast<int>(s.mesh)];
  m.vao.bind();
  glDrawArrays(GL_TRIANGLES, 0, m.count);
  m.vao.release();
}

void Viewport::drawLines(const std::vector<float>& v, GLenum mode, const glm::mat4& vp) {
  if (v.empty()) return;
  lineShader_->bind();
  glUniformMatrix4fv(lineShader_->uniformLocation("viewProjection"), 1, GL_FALSE, glm::value_ptr(vp));
  lineVao_.bind();
  lineVbo_.bind();
  lineVbo_.allocate(v.data(), static_cast<int>(v.size() * sizeof(float)));
  glDrawArrays(mode, 0, static_cast<int>(v.size() / 7));
  lineVao_.release();
}

void Viewport::paintGL() {
  QElapsedTimer timer;
  timer.start();
  const RenderScene& rs = renderScene();
  const QSize target = renderSize_.isValid() ? renderSize_ : size();
  const float w = static_cast<float>(target.width()), h = static_cast<float>(target.height());
  const glm::mat4 vp = camera_.projection(w / std::max(1.0f, h)) * camera_.view();

  glClearColor(0.16f, 0.17f, 0.19f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glEnable(GL_BLEND);
  // Blend colour only: the framebuffer's alpha stays 1, or the window compositor (and grabs)
  // would see through the ghosts.
  glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ZERO, GL_ONE);

  // Ground grid: 10 cm minor lines, 50 cm major lines, the x axis red and the z axis blue.
  std::vector<float> grid;
  if (rs.ground) {
    const float y = rs.groundHeight;
    const float cx = std::round(camera_.target.x * 2) / 2, cz = std::round(camera_.target.z * 2) / 2;
    const int n = 40;
    for (int i = -n; i <= n; ++i) {
      const float s = i * 0.1f;
      const bool major = i % 5 == 0;
      glm::vec4 cx4 = major ? glm::vec4(0.42f, 0.43f, 0.46f, 1) : glm::vec4(0.27f, 0.28f, 0.3f, 1);
      glm::vec4 cz4 = cx4;
      if (std::abs(cz + s) < 1e-4f) cx4 = glm::vec4(0.75f, 0.3f, 0.3f, 1);
      if (std::abs(cx + s) < 1e-4f) cz4 = glm::vec4(0.3f, 0.4f, 0.8f, 1);
      pushLine(grid, {cx - n * 0.1f, y, cz + s}, cx4);
      pushLine(grid, {cx + n * 0.1f, y, cz + s}, cx4);
      pushLine(grid, {cx + s, y, cz - n * 0.1f}, cz4);
      pushLine(grid, {cx + s, y, cz + n * 0.1f}, cz4);
    }
  }
  drawLines(grid, GL_LINES, vp);

  solidShader_->bind();
  glUniformMatrix4fv(solidShader_->uniformLocation("viewProjection"), 1, GL_FALSE, glm::value_ptr(vp));
  const glm::vec3 eye = camera_.eye();
  solidShader_->setUniformValue("eye", QVector3D(eye.x, eye.y, eye.z));
  for (const Solid& s : rs.solids)
    if (!s.ghost) drawSolid(s);

  // Trails, then the translucent ghosts (no depth writes, so they never hide each other).
  for (const Polyline& l : rs.lines) {
    std::vector<float> v;
    for (const glm::vec3& p : l.points) pushLine(v, p, l.color);
    drawLines(v, GL_LINE_STRIP, vp);
  }
  glDepthMask(GL_FALSE);
  solidShader_->bind();
  for (const Solid& s : rs.solids)
    if (s.ghost) drawSolid(s);
  for (const Obstacle& obstacle : rs.obstacles)
    for (const Solid& s : obstacle.boxes) drawSolid(s);
  glDepthMask(GL_TRUE);

  // Pin handles on top of everything: the target and a line from the pinned point.
  glDisable(GL_DEPTH_TEST);
  std::vector<float> pinLines;
  for (const Handle& hd : rs.handles) {
    const glm::vec4 c = hd.selected ? glm::vec4(1.0f, 0.55f, 0.1f, 1) : glm::vec4(1.0f, 0.85f, 0.2f, 1);
    pushLine(pinLines, hd.bodyPoint, c);
    pushLine(pinLines, hd.position, c);
  }
  drawLines(pinLines, GL_LINES, vp);
  solidShader_->bind();
  for (const Handle& hd : rs.handles) {
    const float r = 0.012f * camera_.distance / 2.5f;
    Solid s{Mesh::Sphere, glm::scale(glm::translate(glm::mat4(1.0f), hd.position), glm::vec3(r)),
            hd.selected ? glm::vec4(1.0f, 0.55f, 0.1f, 1) : glm::vec4(1.0f, 0.85f, 0.2f, 1), -1, {}, false};
    drawSolid(s);
  }
  glEnable(GL_DEPTH_TEST);
  lastFrameMs_ = timer.nsecsElapsed() * 1e-6;
}

double Viewport::renderFrameAndFinish() {
  makeCurrent();
  QElapsedTimer timer;
  timer.start();
  glBindFramebuffer(GL_FRAMEBUFFER, defaultFramebufferObject());
  glViewport(0, 0, static_cast<GLsizei>(width() * devicePixelRatio()), static_cast<GLsizei>(height() * devicePixelRatio()));
  paintGL();
  glFinish();
  return timer.nsecsElapsed() * 1e-6;
}

QImage Viewport::renderImage(const QSize& size) {
  makeCurrent();
  // A multisampled offscreen framebuffer of the requested size (the window's own has none),
  // resolved into the image by toImage().
  QOpenGLFramebufferObjectFormat format;
  format.setAttachment(QOpenGLFramebufferObject::CombinedDepthStencil);
  format.setSamples(4);
  QOpenGLFramebufferObject fbo(size, format);
  fbo.bind();
  glViewport(0, 0, size.width(), size.height());
  renderSize_ = size;
  paintGL();
  renderSize_ = QSize();
  QImage image = fbo.toImage();
  fbo.release();
  doneCurrent();
  return image;
}

QPointF Viewport::toPixel(const glm::vec3& p) const {
  const glm::vec2 px = camera_.project(p, static_cast<float>(width()), static_cast<float>(height()));
  return {px.x, px.y};
}

int Viewport::handleAt(const QPointF& pos) {
  const RenderScene& rs = renderScene();
  for (size_t i = 0; i < rs.handles.size(); ++i) {
    const QPointF d = toPixel(rs.handles[i].position) - pos;
    if (std::hypot(d.x(), d.y()) < 10) return static_cast<int>(i);
  }
  return -1;
}

void Viewport::mousePressEvent(QMouseEvent* e) {
  last_ = pressPos_ = e->position();
  const bool orbitButton = e->button() == Qt::MiddleButton ||
                           (e->button() == Qt::LeftButton && (e->modifiers() & Qt::AltModifier));
  if (orbitButton) {
    drag_ = (e->modifiers() & Qt::ShiftModifier) ? Drag::Pan
            : (e->modifiers() & Qt::ControlModifier) ? Drag::Zoom : Drag::Orbit;
  } else if (e->button() == Qt::RightButton) {
    drag_ = Drag::Pan;
  } else if (e->button() == Qt::LeftButton) {
    const int h = handleAt(e->position());
    if (h >= 0) {
      const Handle& hd = renderScene().handles[h];
      drag_ = Drag::Handle;
      dragTerm_ = hd.term;
      ++dragSerial_;  // a new drag: a new undo command, merged only within this drag
      doc_->beginContinuousEdit(dragMergeId());
      doc_->selectTerm(hd.term);
      dragPlanePoint_ = hd.position;
      dragPlaneNormal_ = glm::normalize(camera_.eye() - camera_.target);
    } else if (!(poseTool_ && !pinTool_ && startPose(e->position(), e->modifiers() & Qt::ShiftModifier))) {
      drag_ = Drag::Click;
    }
  }
}

bool Viewport::startPose(const QPointF& pos, bool ik) {
  glm::vec3 o, dir;
  camera_.ray(pos.x(), pos.y(), static_cast<float>(width()), static_cast<float>(height()), &o, &dir);
  const RenderScene& rs = renderScene();
  const std::optional<Pick> pick = pickSolid(rs, o, dir);
  if (!pick) return false;
  const Solid& s = rs.solids[pick->solid];
  const Model<double>& model = doc_->models()[s.character];
  const Eigen::VectorXd q = doc_->posesNow()[s.character];
  const int body = model.bodyIndex(s.body);
  doc_->selectBody(s.character, s.body);
  if (ik) {
    // The grabbed point follows the mouse in the plane facing the camera. With points of the
    // character on the ground now (its contacts at this time, on other bodies than the grabbed
    // one), every joint moves and the root translates, and those points stay planted: pulling a
    // biped's pelvis down crouches it on its feet. Otherwise the chain up to the root turns.
    const Eigen::Vector3d hit(pick->point.x, pick->point.y, pick->point.z);
    IkDrag drag{s.character, body, worldToBody(model, q, body, hit), {}, {}};
    const Scene& scene = doc_->scene();
    const double now = doc_->currentTime();
    Data<double> d(model);
    forwardKinematics(model, d, q.data());
    for (const TermSpec& t : scene.terms) {
      if (!t.enabled || t.kind != TermKind::Contact || t.character != scene.characters[s.character].id ||
          now < t.start - 1e-9 || now > t.end + 1e-9)
        continue;
      const int on = model.bodyIndex(t.body);
      if (on == body) continue;
      for (const Eigen::Vector3d& p : t.points) drag.planted.push_back({on, p, pointPosition(d, on, p)});
    }
    drag.dofs = drag.planted.empty() ? ikChain(model, body) : plantedIkDofs(model);
    if (drag.dofs.empty()) return false;
    drag_ = Drag::PoseIk;
    ik_ = std::move(drag);
    dragPlanePoint_ = pick->point;
    dragPlaneNormal_ = glm::normalize(camera_.eye() - camera_.target);
    return true;
  }
  const std::optional<PoseJoint> joint = poseJoint(model, q, body);
  if (!joint) return false;
  drag_ = Drag::Pose;
  // A joint whose axis points at the viewer turns counter-clockwise on screen as its angle grows.
  const double sign = glm::dot(toGlm(joint->axis), camera_.eye() - camera_.target) >= 0 ? 1.0 : -1.0;
  pose_ = {s.character, *joint, q, 0.0, screenAngle(*joint, pos), sign};
  return true;
}

double Viewport::screenAngle(const PoseJoint& joint, const QPointF& pos) const {
  const QPointF c = toPixel(toGlm(joint.pivot));
  return std::atan2(-(pos.y() - c.y()), pos.x() - c.x());  // screen y grows downwards
}

std::optional<glm::vec3> Viewport::onDragPlane(const QPointF& pos) const {
  glm::vec3 o, dir;
  camera_.ray(pos.x(), pos.y(), static_cast<float>(width()), static_cast<float>(std::max(1, height())), &o, &dir);
  const float denom = glm::dot(dir, dragPlaneNormal_);
  if (std::abs(denom) < 1e-6f) return std::nullopt;  // the ray runs along the plane
  return o + dir * (glm::dot(dragPlanePoint_ - o, dragPlaneNormal_) / denom);
}

void Viewport::dragIk(const QPointF& pos) {
  const std::optional<glm::vec3> at = onDragPlane(pos);
  if (!at) return;
  const glm::vec3 p = *at;
  const Model<double>& model = doc_->models()[ik_.character];
  // From the pose on show, so the chain moves on from where it is (no jumps between branches).
  const PlantedIkResult r = solvePlantedIk(model, doc_->posesNow()[ik_.character], ik_.dofs,
                                           {ik_.body, ik_.local, Eigen::Vector3d(p.x, p.y, p.z)}, ik_.planted);
  doc_->setPosed(ik_.character, r.q);
}

void Viewport::dragPose(const QPointF& pos) {
  const Model<double>& model = doc_->models()[pose_.character];
  // The angle swept around the pivot since the press, unwrapped across +-pi step by step.
  const double now = screenAngle(pose_.joint, pos);
  double step = now - pose_.lastAngle;
  step -= 2 * M_PI * std::round(step / (2 * M_PI));
  pose_.swept += step;
  pose_.lastAngle = now;
  const int dof = pose_.joint.dof;
  Eigen::VectorXd q = pose_.start;
  q[dof] += pose_.sign * pose_.swept;
  const Body<double>& b = model.bodies[model.dofBody[dof]];
  if (b.hasPositionLimits) q[dof] = std::clamp(q[dof], b.lower, b.upper);
  doc_->setPosed(pose_.character, q);
}

void Viewport::mouseMoveEvent(QMouseEvent* e) {
  const QPointF d = e->position() - last_;
  last_ = e->position();
  const float h = static_cast<float>(std::max(1, height()));
  switch (drag_) {
    case Drag::Orbit: camera_.orbit(-d.x() * 0.01f, d.y() * 0.01f); update(); break;
    case Drag::Pan: camera_.pan(d.x() / h, d.y() / h); update(); break;
    case Drag::Zoom: camera_.zoom(std::exp(d.y() * 0.01f)); update(); break;
    case Drag::Handle: {
      const std::optional<glm::vec3> at = onDragPlane(e->position());
      if (!at) break;
      const glm::vec3 p = *at;
      const std::string term = dragTerm_;
      doc_->edit(tr("Move pin"), [&](Scene& s) {
        for (TermSpec& t : s.terms)
          if (t.id == term) t.position = Eigen::Vector3d(p.x, p.y, p.z);
      }, dragMergeId());
      break;
    }
    case Drag::Pose: dragPose(e->position()); break;
    case Drag::PoseIk: dragIk(e->position()); break;
    default: break;
  }
}

void Viewport::mouseReleaseEvent(QMouseEvent* e) {
  if (drag_ == Drag::Click) {
    const QPointF moved = e->position() - pressPos_;
    if (std::hypot(moved.x(), moved.y()) < 4) clickAt(e->position());
  }
  if (drag_ == Drag::Handle) doc_->endContinuousEdit();
  drag_ = Drag::None;
}

bool Viewport::addContactPoint(const Solid& s, const glm::vec3& hit) {
  const std::string term = contactPointTerm_;
  contactPointTerm_.clear();
  const Scene& scene = doc_->scene();
  const auto t = std::find_if(scene.terms.begin(), scene.terms.end(), [&](const TermSpec& x) { return x.id == term; });
  if (t == scene.terms.end() || t->kind != TermKind::Contact || t->body != s.body ||
      scene.characters[s.character].id != t->character) {
    emit contactPointToolDone(QString::fromStdString(term), false);
    return false;  // another body: an ordinary click
  }
  const Model<double>& model = doc_->models()[s.character];
  const Eigen::Vector3d local =
      worldToBody(model, doc_->posesNow()[s.character], model.bodyIndex(s.body), Eigen::Vector3d(hit.x, hit.y, hit.z));
  doc_->edit(tr("Add contact point"), [&](Scene& sc) {
    for (TermSpec& x : sc.terms)
      if (x.id == term) x.points.push_back(local);
  });
  emit contactPointToolDone(QString::fromStdString(term), true);
  return true;
}

void Viewport::clickAt(const QPointF& pos) {
  glm::vec3 o, dir;
  camera_.ray(pos.x(), pos.y(), static_cast<float>(width()), static_cast<float>(height()), &o, &dir);
  const RenderScene& rs = renderScene();
  const std::optional<Pick> pick = pickSolid(rs, o, dir);
  if (!pick) {
    if (!contactPointTerm_.empty()) {  // a click on nothing ends the tool too
      emit contactPointToolDone(QString::fromStdString(contactPointTerm_), false);
      contactPointTerm_.clear();
    }
    doc_->selectBody(doc_->selectedCharacter(), {});
    return;
  }
  const Solid& s = rs.solids[pick->solid];
  if (!contactPointTerm_.empty() && addContactPoint(s, pick->point)) return;
  doc_->selectBody(s.character, s.body);
  if (!pinTool_) return;
  // Pin the clicked point of the body where it is now, at the current time.
  const Model<double>& model = doc_->models()[s.character];
  const Eigen::VectorXd q = doc_->posesNow()[s.character];
  const Eigen::Vector3d world(pick->point.x, pick->point.y, pick->point.z);
  const Eigen::Vector3d local = worldToBody(model, q, model.bodyIndex(s.body), world);
  const std::string id = doc_->uniqueTermId("pin");
  const std::string character = doc_->scene().characters[s.character].id;
  const std::string body = s.body;
  const double t = doc_->currentTime();
  const bool planar = doc_->scene().characters[s.character].root == RootKind::Planar;
  doc_->edit(tr("Add pin"), [&](Scene& sc) {
    TermSpec pin;
    pin.id = id;
    pin.kind = TermKind::Pin;
    pin.character = character;
    pin.body = body;
    pin.time = t;
    pin.point = local;
    pin.position = world;
    if (planar) pin.axes = {true, true, false};
    sc.terms.push_back(pin);
  });
  doc_->selectTerm(id);
  pinTool_ = false;
  emit pinToolUsed();
}

void Viewport::wheelEvent(QWheelEvent* e) {
  camera_.zoom(std::exp(-e->angleDelta().y() / 120.0f * 0.12f));
  update();
}

}  // namespace spacetime::ui
