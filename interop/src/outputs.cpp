// JSON writers for the command-line outputs (see outputs.h).
#include "interop/outputs.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/scene_io.h"
#include "interop/urdf_export.h"
#include "interop/bvh_export.h"
#include "interop/gltf_export.h"
#include "json_stream.h"

namespace spacetime {
namespace {

using json = nlohmann::ordered_json;

}  // namespace

std::string summaryJson(const SolverSummary& s, const ValidityReport& v,
                        const SpacetimeProblem& problem, const std::vector<TranscriptionAttempt>& attempts,
                        const SecondOrderCheck* secondOrder) {
  json j;
  j["method"] = toString(s.method);
  j["converged"] = s.converged;
  j["status"] = toString(s.status);
  j["reason"] = s.reason;
  j["objective"] = s.objective;
  j["iterations"] = s.iterations;
  j["outer_iterations"] = s.outerIterations;
  j["newton_steps"] = s.newtonSteps;
  j["newton_solves"] = s.newtonSolves;  // KKT systems solved; newton_steps counts active-set changes too
  j["chord_steps"] = s.chordSteps;  // steps on the factorisation kept from the warm start's optimum
  j["sqp_steps"] = s.sqpSteps;  // method sqp: its quadratic programs (0: did not run)
  j["sqp_seconds"] = s.sqpSeconds;
  j["qp_seconds"] = s.qpSeconds;
  j["restoration_steps"] = s.restorationSteps;
  j["restoration_seconds"] = s.restorationSeconds;
  j["polished"] = s.polished;
  j["interior_point_iterations"] = s.interiorPointIterations;  // after a stall (0: did not run)
  j["interior_point_seconds"] = s.interiorPointSeconds;
  j["rescued"] = s.rescued;
  j["solve_seconds"] = s.solveSeconds;
  j["jacobian_seconds"] = s.jacobianSeconds;
  j["linear_solver_seconds"] = s.linearSolverSeconds;
  j["max_violation"] = s.maxViolation;
  j["worst_constraint"] = s.worstConstraint;
  // Unmet constraints of a solve that stopped short, largest first (empty when converged).
  json violated = json::array();
  for (const ViolatedConstraint& v : s.violated) violated.push_back({{"constraint", v.label}, {"violation", v.violation}});
  j["violated_constraints"] = violated;
  j["variables"] = problem.variables().size();
  j["residual_blocks"] = problem.residuals().size();
  // Each contact's interval as solved: a free end (freeEnd) is where the solver let go.
  json contacts = json::array();
  for (const ContactVariables& ct : problem.contacts()) {
    const TermSpec& term = problem.scene().terms[ct.term];
    json jc = {{"term", term.id}, {"start", ct.start}, {"end", ct.end}, {"free_end", ct.freeEnd >= 0}};
    if (ct.freeEnd >= 0) {
      const FreeEnd& e = problem.freeEnds()[ct.freeEnd];
      jc["scene_end"] = term.end;
      jc["end_bounds"] = json::array({e.lower, e.upper});
    }
    contacts.push_back(jc);
  }
  j["contacts"] = contacts;
  // The transcription of the motion written, and every one the solve tried (refinement.h).
  const TranscriptionSpec& spec = problem.scene().transcription;
  j["transcription"] = {{"control_points_per_second", spec.controlPointsPerSecond},
                        {"samples_per_segment", spec.samplesPerSegment},
                        {"leg_bubbles", spec.legBubbles},
                        {"segments", problem.transcription().motion.segmentCount()},
                        {"knots", spec.knots}};
  json refinement = json::array();
  for (const TranscriptionAttempt& a : attempts)
    refinement.push_back({{"control_points_per_second", a.controlPointsPerSecond},
                          {"samples_per_segment", a.samplesPerSegment},
                          {"segments", a.segments},
                          {"non_uniform", a.nonUniform},
                          {"leg_bubbles", a.legBubbles},
                          {"why", a.why},
                          {"status", toString(a.status)},
                          {"converged", a.converged},
                          {"too_coarse", a.tooCoarse},
                          {"valid", a.valid},
                          {"objective", a.objective},
                          {"max_violation", a.maxViolation},
                          {"max_unactuated_residual_dense", a.maxUnactuatedResidualDense},
                          {"iterations", a.iterations},
                          {"newton_steps", a.newtonSteps},
                          {"seconds", a.seconds},
                          {"kept", a.kept}});
  j["refinement"] = refinement;
  if (secondOrder) {
    const SecondOrderCheck& c = *secondOrder;
    // Infinite smallest eigenvalue (no free direction) is written as null: JSON has no infinity.
    auto number = [](double x) { return std::isfinite(x) ? json(x) : json(nullptr); };
    j["second_order"] = {{"checked", c.checked},
                         {"strict_minimum", c.strictMinimum},
                         {"strict_motion", c.strictMinimum || c.strictMotion},
                         {"free_force_directions", c.freeForceDirections},
                         {"smallest_eigenvalue", number(c.smallestEigenvalue)},
                         {"largest_eigenvalue", number(c.largestEigenvalue)},
                         {"rounding_floor", c.roundingFloor},
                         {"free_directions", c.nullity},
                         {"active_constraints", c.constraints},
                         {"dependent_constraints", c.dependent},
                         {"weakly_active", c.weaklyActive},
                         {"direction", c.direction},
                         {"stationarity", c.stationarity},
                         {"seconds", c.seconds},
                         {"reason", c.reason}};
  }
  json val;
  val["dense_factor"] = v.denseFactor;
  val["max_unactuated_residual_samples"] = v.maxUnactuatedResidualSamples;
  val["max_unactuated_residual_dense"] = v.maxUnactuatedResidualDense;
  val["worst_dense_time"] = v.worstDenseTime;
  val["max_pin_error"] = v.maxPinError;
  val["max_contact_slip"] = v.maxContactSlip;
  val["max_contact_penetration"] = v.maxContactPenetration;
  val["min_normal_force"] = v.minNormalForce;
  val["max_friction_ratio"] = v.maxFrictionRatio;
  val["max_cone_violation"] = v.maxConeViolation;
  val["contacts_push_only"] = v.contactsPushOnly;
  val["contacts_in_friction_cone"] = v.contactsInFrictionCone;
  val["max_clearance_violation"] = v.maxClearanceViolation;
  if (!v.worstClearanceTerm.empty()) {
    val["worst_clearance_time"] = v.worstClearanceTime;
    val["worst_clearance_term"] = v.worstClearanceTerm;
  }
  val["max_rest_speed"] = v.maxRestSpeed;
  val["max_ground_penetration"] = v.maxGroundPenetration;
  if (!v.worstGroundPenetrationBody.empty()) {
    val["worst_ground_penetration_time"] = v.worstGroundPenetrationTime;
    val["worst_ground_penetration_body"] = v.worstGroundPenetrationBody;
  }
  if (v.hasPositionLimits) {
    val["max_joint_limit_excess"] = v.maxJointLimitExcess;
    if (!v.worstJointLimit.empty()) {
      val["worst_joint_limit_time"] = v.worstJointLimitTime;
      val["worst_joint_limit"] = v.worstJointLimit;
    }
  }
  if (v.hasSpeedLimits) {
    val["max_joint_speed_excess"] = v.maxJointSpeedExcess;
    if (!v.worstJointSpeed.empty()) {
      val["worst_joint_speed_time"] = v.worstJointSpeedTime;
      val["worst_joint_speed"] = v.worstJointSpeed;
    }
  }
  val["max_forward_simulation_error"] = v.maxForwardSimulationError;
  json flights = json::array();
  for (const FlightCheck& f : v.flights)
    flights.push_back({{"character", f.character},
                       {"start", f.start},
                       {"end", f.end},
                       {"max_position_error", f.maxPositionError},
                       {"diverged", f.diverged},
                       {"divergence_time", f.diverged ? json(f.divergenceTime) : json(nullptr)},
                       {"max_root_lift", f.maxRootLift}});
  val["flights"] = flights;
  val["forward_simulation_diverged"] = v.forwardSimulationDiverged;
  json formulas = json::array();
  for (const FormulaCheck& f : v.formulas) {
    json jf = {{"term", f.term}, {"max_violation", f.maxViolation}, {"worst_time", f.worstTime}};
    if (!f.error.empty()) jf["error"] = f.error;
    formulas.push_back(jf);
  }
  val["formulas"] = formulas;
  val["max_formula_violation"] = v.maxFormulaViolation;
  // The same as a checklist with the limits people judge by (validityChecklist).
  json checks = json::array();
  bool valid = true;
  for (const ValidityCheck& c : validityChecklist(v)) {
    json jc = {{"check", c.name}, {"value", c.value}, {"limit", c.limit}, {"unit", c.unit}, {"pass", c.pass}};
    if (c.time) jc["time"] = *c.time;  // where it is worst
    checks.push_back(jc);
    valid = valid && c.pass;
  }
  val["checks"] = checks;
  val["valid"] = valid;
  json impacts = json::array();
  for (const ImpactCheck& i : v.impacts)
    impacts.push_back({{"contact", i.contact},
                       {"time", i.time},
                       {"speed_before", i.speedBefore},
                       {"min_normal_impulse", i.minNormalImpulse},
                       {"max_friction_ratio", i.maxFrictionRatio},
                       {"max_balance_error", i.maxBalanceError},
                       {"max_speed_after", i.maxSpeedAfter},
                       {"max_joint_impulse", i.maxJointImpulse}});
  val["impacts"] = impacts;
  j["validity"] = val;
  return j.dump(2) + "\n";
}

std::string motionCsv(const Animation& animation) {
  std::string out = "time";
  static const char* kinds[] = {"q", "qd", "qdd", "tau"};
  for (const CharacterAnimation& c : animation.characters)
    for (const std::string& dof : c.dofs)
      for (const char* k : kinds) out += "," + c.name + "." + dof + "." + k;
  out += "\n";
  if (animation.characters.empty()) return out;
  char buf[32];
  const std::vector<double>& times = animation.characters.front().times;
  for (size_t f = 0; f < times.size(); ++f) {
    std::snprintf(buf, sizeof buf, "%.9g", times[f]);
    out += buf;
    for (const CharacterAnimation& c : animation.characters)
      for (Eigen::Index d = 0; d < c.q.cols(); ++d)
        for (const Eigen::MatrixXd* m : {&c.q, &c.qd, &c.qdd, &c.tau}) {
          std::snprintf(buf, sizeof buf, ",%.12g", (*m)(static_cast<Eigen::Index>(f), d));
          out += buf;
        }
    out += "\n";
  }
  return out;
}

std::string motionJson(const Animation& animation) {
  std::string text;
  JsonStream out(&text);
  auto rows = [&](const Eigen::MatrixXd& m) {
    out.beginArray();
    for (Eigen::Index r = 0; r < m.rows(); ++r) out.array(m.row(r));
    out.endArray();
  };
  auto points = [&](const std::vector<Eigen::Vector3d>& v) {
    out.beginArray();
    for (const Eigen::Vector3d& x : v) out.array(x);
    out.endArray();
  };
  out.beginObject();
  out.key("formatVersion");
  out.value(1);
  out.key("characters");
  out.beginArray();
  for (const CharacterAnimation& c : animation.characters) {
    out.beginObject();
    out.key("name");
    out.value(c.name);
    out.key("urdf");
    out.value(c.name + ".urdf");
    out.key("gravity");
    out.array(c.gravity);
    out.key("dofs");
    out.beginArray();
    for (const std::string& d : c.dofs) out.value(d);
    out.endArray();
    out.key("actuated");
    out.beginArray();
    for (bool a : c.actuated) out.value(a);
    out.endArray();
    out.key("times");
    out.beginArray();
    for (double t : c.times) out.value(t);
    out.endArray();
    out.key("q");
    rows(c.q);
    out.key("qd");
    rows(c.qd);
    out.key("qdd");
    rows(c.qdd);
    // q-dot's left limit where it differs from qd: the frames at a touch-down's impact (at the
    // root's other breakpoints the two sides differ by rounding only, ~1e-15).
    out.key("qdBefore");
    out.beginArray();
    if (c.qdBefore.rows() == c.qd.rows())
      for (Eigen::Index f = 0; f < c.qd.rows(); ++f)
        if ((c.qdBefore.row(f) - c.qd.row(f)).cwiseAbs().maxCoeff() > 1e-9 * (1 + c.qd.row(f).cwiseAbs().maxCoeff())) {
          out.beginObject();
          out.key("frame");
          out.value(static_cast<int>(f));
          out.key("qd");
          out.array(c.qdBefore.row(f));
          out.endObject();
        }
    out.endArray();
    out.key("tau");
    rows(c.tau);
    out.key("contacts");
    out.beginArray();
    for (const ContactTrack& t : c.contacts) {
      out.beginObject();
      out.key("term");
      out.value(t.term);
      out.key("link");
      out.value(t.link);
      out.key("pointIndex");
      out.value(t.pointIndex);
      out.key("start");  // the interval as solved (with a free end, where it let go)
      out.value(t.start);
      out.key("end");
      out.value(t.end);
      out.key("freeEnd");
      out.value(t.freeEnd);
      out.key("point");
      points(t.position);
      out.key("force");
      points(t.force);
      if (t.impact) {
        out.key("impact");
        out.beginObject();
        out.key("time");
        out.value(t.impactTime);
        out.key("impulse");
        out.array(t.impulse);
        out.endObject();
      }
      out.endObject();
    }
    out.endArray();
    out.endObject();
  }
  out.endArray();
  out.endObject();
  return text + "\n";
}

namespace {

// What a solve writes into its output directory.
bool isSolveOutput(const std::string& name) {
  auto endsWith = [&](const char* suffix) {
    const std::string x(suffix);
    return name.size() > x.size() && name.compare(name.size() - x.size(), x.size(), x) == 0;
  };
  return name == "summary.json" || name == "motion.json" || name == "motion.glb" || name == "scene.json" ||
         endsWith(".urdf") || endsWith(".bvh");
}

// The directory as an absolute path without a trailing separator.
std::filesystem::path outputPath(const std::string& dir) {
  std::filesystem::path p = std::filesystem::absolute(dir).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  return p;
}

bool fsyncPath(const std::filesystem::path& p) {
  const int fd = ::open(p.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) return false;
  const bool ok = ::fsync(fd) == 0;
  ::close(fd);
  return ok;
}

}  // namespace

bool checkOutputDirectory(const std::string& dir, std::string* error) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path target = outputPath(dir);
  if (fs::exists(target, ec)) {
    if (!fs::is_directory(target, ec)) {
      *error = "--out " + dir + " is a file, not a directory";
      return false;
    }
    for (fs::directory_iterator it(target, ec), end; !ec && it != end; it.increment(ec)) {
      const std::string name = it->path().filename().string();
      if (!isSolveOutput(name)) {
        *error = "--out " + dir + " holds '" + name.substr(0, 100) +
                 "', which a solve does not write; the outputs replace the directory as a whole, so give a new "
                 "or empty directory or one an earlier solve wrote";
        return false;
      }
    }
  }
  // The new set is written beside the directory, then swapped in: its parent must be writable.
  fs::path parent = target.parent_path();
  while (!parent.empty() && !fs::exists(parent, ec) && parent != parent.parent_path()) parent = parent.parent_path();
  if (!fs::is_directory(parent, ec) || ::access(parent.c_str(), W_OK) != 0) {
    *error = "cannot write the outputs: " + parent.string() + " is not a writable directory";
    return false;
  }
  return true;
}

std::string resumedScenePath(const std::string& path, std::string* error) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path given(path);
  const bool directory = fs::is_directory(given, ec);
  const fs::path dir = directory ? given : given.parent_path().empty() ? fs::path(".") : given.parent_path();
  const bool solveOutput = fs::exists(dir / "summary.json", ec);
  if (!directory && (!solveOutput || given.filename() == "scene.json" || !isSolveOutput(given.filename().string())))
    return path;
  if (!solveOutput) {
    *error = path + " is a directory, not a solve's output (no summary.json in it): give a solved scene.json";
    return {};
  }
  const fs::path scene = dir / "scene.json";
  if (!fs::is_regular_file(scene, ec)) {
    *error = path + " is " + (directory ? "a solve's output directory" : "a solve's output") +
             ", but the scene.json holding that solve's state is missing from " + dir.string();
    return {};
  }
  return scene.string();
}

bool writeSolveOutputs(const SpacetimeProblem& problem, const SolverSummary& summary,
                       const ValidityReport& validity, const OutputOptions& options, const std::string& dir,
                       std::string* error, std::string* warning,
                       const std::vector<TranscriptionAttempt>& attempts, const SecondOrderCheck* secondOrder) {
  namespace fs = std::filesystem;
  if (!checkOutputDirectory(dir, error)) return false;
  // Build every file's contents first, then write them; a failure names the file.
  std::vector<std::pair<std::string, std::string>> files;
  const Animation animation = sampleAnimation(problem, options.motionRate);
  const Animation bvhFrames = sampleAnimationAt(problem, frameTimes(problem.scene(), options.bvhRate));
  const Animation gltfKeys = sampleAnimationAt(problem, gltfKeyTimes(problem, options.gltfRate));
  for (size_t c = 0; c < problem.characters().size(); ++c) {
    const Model<double>& model = *problem.characters()[c].model;
    const CharacterSpec& spec = problem.scene().characters[c];
    const UrdfExport urdf = exportUrdf(model, spec, UrdfOptions{options.urdfZUp});
    if (!urdf.warning.empty() && warning) *warning += urdf.warning + "\n";
    files.emplace_back(model.name + ".urdf", urdf.xml);
    files.emplace_back(model.name + ".bvh", motionBvh(model, spec, bvhFrames.characters[c]));
  }
  std::vector<const Model<double>*> models;
  for (const CharacterVariables& c : problem.characters()) models.push_back(c.model.get());
  files.emplace_back("motion.json", motionJson(animation));
  files.emplace_back("motion.glb", motionGlb(problem.scene(), models, gltfKeys));
  // The scene solved (with the transcription of the motion written) and the solver's state, so
  // that `spacetime-cli solve --init DIR/scene.json` resumes exactly where this solve stopped.
  Scene solved = problem.scene();
  const SolutionState state = problem.state();
  solved.solution = StoredSolution{state.variables, state.multipliers, state.rho, summary.converged};
  files.emplace_back("scene.json", sceneToJson(solved));
  files.emplace_back("summary.json", summaryJson(summary, validity, problem, attempts, secondOrder));

  // All or nothing: the new set goes into a fresh directory beside DIR (.DIR.new-PID), every file
  // and the directory flushed to disk, then takes DIR's place in one atomic exchange
  // (renameat2 RENAME_EXCHANGE); the old set, now in the temporary, is removed. A killed run
  // leaves DIR complete, old or new; its temporary is removed by the next run.
  const fs::path target = outputPath(dir);
  const fs::path parent = target.parent_path();
  const std::string name = target.filename().string();
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) {
    *error = "cannot create output directory " + parent.string() + ": " + ec.message();
    return false;
  }
  removeStaleTemporaries(parent.string(), "." + name + ".new-");
  removeStaleTemporaries(parent.string(), "." + name + ".old-");
  const fs::path fresh = parent / ("." + name + ".new-" + std::to_string(::getpid()));
  fs::remove_all(fresh, ec);
  fs::create_directory(fresh, ec);
  if (ec) {
    *error = "cannot create " + fresh.string() + ": " + ec.message();
    return false;
  }
  auto abandon = [&](const std::string& why) {
    *error = why;
    std::error_code ignored;
    fs::remove_all(fresh, ignored);
    return false;
  };
  for (const auto& [file, text] : files)
    if (!writeFileAtomically((fresh / file).string(), text, error)) return abandon(*error);
  if (!fsyncPath(fresh)) return abandon("cannot flush " + fresh.string() + ": " + std::strerror(errno));
  if (!fs::exists(target, ec)) {
    if (::rename(fresh.c_str(), target.c_str()) != 0)
      return abandon("cannot create " + target.string() + ": " + std::strerror(errno));
  } else if (::renameat2(AT_FDCWD, fresh.c_str(), AT_FDCWD, target.c_str(), RENAME_EXCHANGE) != 0) {
    // A file system without the exchange: move the old set aside, then the new one in. A kill
    // between the two renames leaves DIR missing and both sets beside it.
    const fs::path old = parent / ("." + name + ".old-" + std::to_string(::getpid()));
    if (::rename(target.c_str(), old.c_str()) != 0 || ::rename(fresh.c_str(), target.c_str()) != 0)
      return abandon("cannot replace " + target.string() + ": " + std::strerror(errno));
    fs::remove_all(old, ec);
  }
  fs::remove_all(fresh, ec);  // the old set, after the exchange
  fsyncPath(parent);
  return true;
}

}  // namespace spacetime
