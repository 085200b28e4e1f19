// spacetime-cli: solve a scene headless and write its outputs.
//
//   spacetime-cli solve SCENE.json --out DIR [--rate HZ] [--bvh-rate HZ] [--gltf-rate HZ]
//                       [--urdf-z-up] [--threads N] [--max-seconds S] [--quiet] [--no-polish]
//                       [--max-refinements N] [--init SOLVED.json] [--method al|ipopt|sqp|witkin-kass]
//                       [--second-order]
//
// Writes DIR/summary.json, DIR/motion.json, DIR/motion.glb, DIR/scene.json (the scene with the
// solver's state) and DIR/<character>.urdf and .bvh. A solve starts from --init's stored
// solution (an earlier run's DIR or DIR/motion.json stand for its DIR/scene.json; a motion.json
// alone starts from its sampled motion, re-fitted), else from the scene's own (an editor save),
// else from the default guess. Progress (iteration,
// objective, violation) goes to stderr unless --quiet. Exit status: 0 converged and every
// validity check passes; 1 the outputs could not be written; 2 bad input (a one-line reason,
// before anything is written); 3 the solve did not converge; 4 it converged but the validity
// report fails - the constraints hold at the samples while the motion is not physical between
// them (a transcription too coarse for it), which a batch job must not take for a good motion.
// Before exiting 3 or 4 the solve refines the transcription (solver/refinement.h) up to
// --max-refinements times and writes the best motion it found.
#include <algorithm>
#include <chrono>
#include <new>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>

#include "core/atomic_file.h"
#include "core/scene_io.h"
#include "interop/motion_import.h"
#include "solver/motion_source.h"
#include "solver/augmented_lagrangian.h"
#include "interop/outputs.h"
#include "solver/interior_point.h"
#include "solver/refinement.h"
#include "solver/second_order.h"
#include "solver/validity.h"

using namespace spacetime;

namespace {

#define SPACETIME_CLI_USAGE \
  "usage: spacetime-cli solve SCENE.json --out DIR [--rate HZ] [--bvh-rate HZ] [--gltf-rate HZ]\n" \
  "                          [--urdf-z-up] [--threads N] [--max-seconds S] [--quiet]\n" \
  "                          [--no-polish] [--max-refinements N] [--init SOLVED.json]\n" \
  "                          [--method al|ipopt|sqp|witkin-kass] [--second-order]\n"

constexpr const char* kHelp =
    SPACETIME_CLI_USAGE
    "\n"
    "Solves a Spacetime scene headless and writes DIR/summary.json, DIR/motion.json, one URDF and\n"
    "one BVH per character, DIR/motion.glb and DIR/scene.json (the scene with the solver's state).\n"
    "  --rate HZ          frames per second of motion.json (default 1000)\n"
    "  --bvh-rate HZ      frames per second of the BVH files (default: the scene's time.frameRate, 24)\n"
    "  --gltf-rate HZ     motion.glb's key grid per second (default: the frame rate; cubic keys, plus the\n"
    "                     splines' knots and denser keys in fast motion)\n"
    "  --urdf-z-up        URDF files Z-up (the scene turned +90 degrees about X), so tools'\n"
    "                     default gravity along -Z is the scene's; default: Y-up as the scene\n"
    "  --threads N        Ceres evaluation threads (default 2)\n"
    "  --max-seconds S    wall-clock budget of the solve (default: the scene's solver.maxSeconds,\n"
    "                     else 300)\n"
    "  --quiet            no progress on stderr\n"
    "  --no-polish        the augmented Lagrangian without the Newton polish\n"
    "  --method M         al: augmented Lagrangian with Newton polish; ipopt: IPOPT's interior\n"
    "                     point with exact Hessians; sqp: sequential quadratic programming, the\n"
    "                     augmented Lagrangian where its steps fail (default: the scene's\n"
    "                     solver.method, else al)\n"
    "  --max-refinements N  finer transcriptions tried when the motion fails the validity report\n"
    "                     or the solve stalls (default: the scene's solver.maxRefinements, else\n"
    "                     3; 0: only the scene's transcription)\n"
    "  --init SOLVED.json start from the solution stored in a scene: DIR/scene.json of an earlier\n"
    "                     solve (resumes it exactly when the scene is the same) or an editor save;\n"
    "                     DIR or DIR/motion.json of a solve stand for its DIR/scene.json; a\n"
    "                     motion.json alone starts from its motion, fitted to this scene.\n"
    "                     Without it a scene's own stored solution is the start.\n"
    "  --second-order     after a converged solve, check that the motion is a strict local\n"
    "                     minimum (the reduced Hessian of the Lagrangian positive definite) and\n"
    "                     write the check to summary.json as second_order\n"
    "Exit status: 0 converged and valid; 1 outputs not written; 2 bad input or options (nothing\n"
    "written); 3 not converged or out of time (outputs written); 4 converged but the validity\n"
    "report fails (outputs written).\n";

int usage(const char* why) {
  std::fprintf(stderr, "spacetime-cli: %s\n" SPACETIME_CLI_USAGE, why);
  return 2;
}

}  // namespace

int run(int argc, char** argv);

int main(int argc, char** argv) {
  // Out of memory anywhere (a scene within SceneLimits on a small machine) is reported, and
  // nothing is written: the outputs are built in memory before any file is.
  try {
    return run(argc, argv);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "spacetime-cli: out of memory; nothing written\n");
    return 3;
  }
}

int run(int argc, char** argv) {
  const auto started = std::chrono::steady_clock::now();  // --max-seconds bounds the whole run
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]) == "--help" || std::string(argv[i]) == "-h") {
      std::fputs(kHelp, stdout);
      return 0;
    }
  if (argc < 2 || std::string(argv[1]) != "solve") return usage("expected the command 'solve'");
  std::string scenePath, outDir;
  OutputOptions outputs;
  bool bvhRateGiven = false, gltfRateGiven = false;  // else the scene's frame rate
  // Ceres evaluates residual blocks on `threads` threads (kernels are thread-safe). 2 suits this
  // 2-core machine; a render farm running one solve per core wants 1.
  int threads = 2;
  double maxSeconds = -1;  // --max-seconds: overrides the scene's solver.maxSeconds
  bool quiet = false;
  bool polish = true;  // --no-polish: the augmented Lagrangian alone (to compare)
  int maxRefinements = -1;  // --max-refinements: overrides the scene's solver.maxRefinements
  std::string initPath;  // --init: a scene holding a stored solution
  std::string initGiven;  // --init as given: that scene, or a solve's output standing for it
  std::string method;    // --method: overrides the scene's solver.method
  bool secondOrder = false;  // --second-order: check the converged motion is a strict local minimum
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out" && i + 1 < argc) outDir = argv[++i];
    else if ((a == "--rate" || a == "--bvh-rate" || a == "--gltf-rate") && i + 1 < argc) {
      char* end = nullptr;
      const double rate = std::strtod(argv[++i], &end);
      if (!end || *end || !(rate > 0) || rate > 1e5) return usage((a + " must be a number of frames per second in (0, 100000]").c_str());
      (a == "--rate" ? outputs.motionRate : a == "--bvh-rate" ? outputs.bvhRate : outputs.gltfRate) = rate;
      bvhRateGiven = bvhRateGiven || a == "--bvh-rate";
      gltfRateGiven = gltfRateGiven || a == "--gltf-rate";
    } else if (a == "--threads" && i + 1 < argc) {
      char* end = nullptr;
      const long n = std::strtol(argv[++i], &end, 10);
      if (!end || *end || n < 1 || n > 256) return usage("--threads must be a whole number in [1, 256]");
      threads = static_cast<int>(n);
    } else if (a == "--max-seconds" && i + 1 < argc) {
      char* end = nullptr;
      maxSeconds = std::strtod(argv[++i], &end);
      if (!end || *end || !(maxSeconds > 0) || maxSeconds > 1e7) return usage("--max-seconds must be a number of seconds in (0, 1e7]");
    } else if (a == "--quiet") quiet = true;
    else if (a == "--no-polish") polish = false;
    else if (a == "--urdf-z-up") outputs.urdfZUp = true;
    else if (a == "--max-refinements" && i + 1 < argc) {
      char* end = nullptr;
      const long n = std::strtol(argv[++i], &end, 10);
      if (!end || *end || n < 0 || n > SolverSpec::kMaxRefinements)
        return usage("--max-refinements must be a whole number in [0, 10]");
      maxRefinements = static_cast<int>(n);
    }
    else if (a == "--init" && i + 1 < argc) initPath = argv[++i];
    else if (a == "--second-order") secondOrder = true;
    else if (a == "--method" && i + 1 < argc) {
      method = argv[++i];
      SolverMethod m;
      if (!parseSolverMethod(method, &m)) return usage("--method must be al, ipopt, sqp or witkin-kass");
    }
    else if (!a.empty() && a[0] == '-') return usage(("unknown option " + a).c_str());
    else if (scenePath.empty()) scenePath = a;
    else return usage(("unexpected argument " + a).c_str());
  }
  if (scenePath.empty()) return usage("missing SCENE.json");
  if (outDir.empty()) return usage("missing --out DIR");

  const SceneLoadResult loaded = loadSceneFile(scenePath);
  if (!loaded.scene) {
    std::fprintf(stderr, "spacetime-cli: %s\n", loaded.error.c_str());
    return 2;
  }
  std::string error;
  std::unique_ptr<SpacetimeProblem> problem = SpacetimeProblem::build(*loaded.scene, &error);
  if (!problem) {
    std::fprintf(stderr, "spacetime-cli: %s: %s\n", scenePath.c_str(), error.c_str());
    return 2;
  }
  // The starting point: --init's stored solution, else the scene's own, else the default guess.
  std::optional<Scene> start;
  std::optional<Animation> startMotion;
  if (!initPath.empty()) {
    // A solve's output directory or its motion.json resumes from the scene.json written with it.
    initGiven = initPath;
    initPath = resumedScenePath(initGiven, &error);
    if (initPath.empty()) {
      std::fprintf(stderr, "spacetime-cli: --init: %s\n", error.c_str());
      return 2;
    }
    std::string text;
    if (!readWholeFile(initPath, &text, &error)) {
      std::fprintf(stderr, "spacetime-cli: --init: %s\n", error.c_str());
      return 2;
    }
    MotionLoadResult motion = parseMotionJson(text, initPath);
    if (motion.motionFile) {
      // A motion file without its run's scene.json (copied out, or written by another tool in
      // the same contract): its sampled motion and contact forces, re-fitted below.
      if (!motion.animation) {
        std::fprintf(stderr, "spacetime-cli: --init: %s\n", motion.error.c_str());
        return 2;
      }
      startMotion = std::move(motion.animation);
    } else {
      const SceneLoadResult init = parseScene(text, initPath);
      if (!init.scene) {
        std::fprintf(stderr, "spacetime-cli: --init: %s\n", init.error.c_str());
        return 2;
      }
      if (!init.scene->solution) {
        std::fprintf(stderr, "spacetime-cli: --init: %s holds no solution (expected DIR/scene.json of a solve, a "
                     "motion.json, or a scene the editor saved after solving)\n", initPath.c_str());
        return 2;
      }
      start = *init.scene;
    }
  } else if (loaded.scene->solution) {
    start = *loaded.scene;
  }
  if (!checkOutputDirectory(outDir, &error)) {
    std::fprintf(stderr, "spacetime-cli: %s\n", error.c_str());
    return 2;
  }
  if (!bvhRateGiven) outputs.bvhRate = loaded.scene->frameRate;
  if (!gltfRateGiven) outputs.gltfRate = loaded.scene->frameRate;
  SolverOptions options = solverOptionsFor(loaded.scene->solver);
  options.threads = threads;
  if (maxSeconds > 0) options.maxSeconds = maxSeconds;
  // In budget seconds: an instrumented build's stretched budget counts its setup stretched too.
  options.spentSeconds = budgetSecondsSince(started);
  options.newtonPolish = polish;
  if (!method.empty()) parseSolverMethod(method, &options.method);
  // What the interior point cannot take is refused before anything is solved or written.
  if (options.method == SolverMethod::InteriorPoint) {
    if (!interiorPointAvailable()) return usage("--method ipopt: this build has no IPOPT (install coinor-libipopt-dev and rebuild)");
    if (!problem->freeEnds().empty()) {
      std::fprintf(stderr, "spacetime-cli: %s: the interior-point method does not handle free contact ends (freeEnd); use --method al\n",
                   scenePath.c_str());
      return 2;
    }
  }
  if (start) {
    const StoredSolution& s = *start->solution;
    const SpacetimeProblem::WarmStart how = problem->warmStartFrom(*start, {s.variables, s.multipliers, s.rho, nullptr});
    options.warmStart = how != SpacetimeProblem::WarmStart::None;
    if (!quiet)
      std::fprintf(stderr, "starting from %s%s: %s\n", initPath.empty() ? "the scene's stored solution" : initPath.c_str(),
                   initGiven == initPath ? "" : (" (for --init " + initGiven + ")").c_str(),
                   how == SpacetimeProblem::WarmStart::Exact      ? "its solver state, exactly"
                   : how == SpacetimeProblem::WarmStart::Refitted ? "its motion, re-fitted to this transcription"
                                                                  : "nothing in common with this scene; the default guess");
  }
  if (startMotion) {
    const int matched = startFromMotion(*problem, *startMotion);
    options.warmStart = matched > 0;
    // The scene's method as methodForMotionStart chooses it (a motion file has no multipliers);
    // an explicit --method is kept, and the methods that read multipliers get estimated ones.
    const bool toSqp = matched > 0 && method.empty() && methodForMotionStart(options.method) != options.method;
    if (toSqp) options.method = methodForMotionStart(options.method);
    std::string how = "no character of this scene in it (matched by id and dof count); the default guess";
    if (matched > 0) {
      how = "its sampled motion and contact forces, fitted to this transcription; ";
      if (const std::optional<MultiplierEstimate> e = multipliersForMotionStart(*problem, options)) {
        char text[160];
        std::snprintf(text, sizeof text, "multipliers estimated there (stationarity %.2g, %d inequalities at their bound)",
                      e->stationarity, e->active);
        how += e->ok ? text : "no multiplier estimate (the rows are not finite)";
      } else {
        how += toSqp ? "solved by sqp, whose programs compute the multipliers (--method al to keep al)"
                     : "the method computes the multipliers";
      }
    }
    if (!quiet) std::fprintf(stderr, "starting from %s: %s\n", initPath.c_str(), how.c_str());
  }
  ProgressCallback progress = nullptr;
  if (!quiet)
    progress = [](const IterationReport& r) {
      std::fprintf(stderr, "iteration %4d  outer %2d  objective %.6g  violation %.3g  penalty %.3g\n",
                   r.iterations, r.outer, r.objective, r.maxViolation, r.rho);
      return true;
    };
  RefinementOptions refinement = refinementOptionsFor(loaded.scene->solver);
  if (maxRefinements >= 0) refinement.maxRefinements = maxRefinements;
  RefinedSolve solved = solveRefined(std::move(problem), options, refinement, progress);
  problem = std::move(solved.problem);
  const SolverSummary& summary = solved.summary;
  const ValidityReport& validity = solved.validity;
  if (solved.attempts.size() > 1)  // the transcriptions tried, when the solve refined
    for (const TranscriptionAttempt& a : solved.attempts)
      std::fprintf(stderr, "transcription %g control points/s%s, %d segments, s = %d%s: %s%s, objective %.9g, dense-grid residual %.3g of weight, %.3f s%s\n",
                   a.controlPointsPerSecond, a.nonUniform ? " split where the residual was large" : "", a.segments,
                   a.samplesPerSegment, a.legBubbles ? ", leg bubbles" : "",
                   a.tooCoarse ? "stopped early, too coarse" : toString(a.status).c_str(),
                   a.converged ? (a.valid ? ", valid" : ", not valid") : "", a.objective,
                   a.maxUnactuatedResidualDense, a.seconds, a.kept ? " (kept)" : "");
  std::optional<SecondOrderCheck> check;
  if (secondOrder) {
    if (summary.converged) {
      check = checkSecondOrder(*problem, threads);
    } else {
      check = SecondOrderCheck();
      check->reason = "not run: the solve did not converge to a KKT point";
    }
  }
  std::string warning;
  if (!writeSolveOutputs(*problem, summary, validity, outputs, outDir, &error, &warning, solved.attempts,
                         check ? &*check : nullptr)) {
    std::fprintf(stderr, "spacetime-cli: %s\n", error.c_str());
    return 1;
  }
  if (!warning.empty()) std::fprintf(stderr, "spacetime-cli: warning: %s", warning.c_str());
  std::fprintf(stderr,
               "%s: %s\n  objective %.9g, max violation %.3g, %d iterations, %.3f s\n"
               "  dense-grid unactuated residual %.3g of weight, forward-simulation error %.3g\n",
               summary.converged ? "converged" : "NOT converged", summary.reason.c_str(),
               summary.objective, summary.maxViolation, summary.iterations, summary.solveSeconds,
               validity.maxUnactuatedResidualDense, validity.maxForwardSimulationError);
  for (const ContactVariables& ct : problem->contacts())
    if (ct.freeEnd >= 0)
      std::fprintf(stderr, "  contact '%s' lifts off at %.4f s (scene end %.4f s)\n",
                   loaded.scene->terms[ct.term].id.c_str(), ct.end, loaded.scene->terms[ct.term].end);
  const std::vector<ValidityCheck> checks = validityChecklist(validity);
  std::string failing;
  for (const ValidityCheck& c : checks)
    if (!c.pass) failing += "\n    " + c.name + ": " + (c.yesNo ? "no" : std::to_string(c.value) + " " + c.unit + " (limit " + std::to_string(c.limit) + ")");
  const auto passing = std::count_if(checks.begin(), checks.end(), [](const ValidityCheck& c) { return c.pass; });
  std::fprintf(stderr, "  validity: %zd of %zu checks pass%s\n", static_cast<std::ptrdiff_t>(passing), checks.size(),
               failing.empty() ? "" : ("; failing:" + failing).c_str());
  if (check)
    std::fprintf(stderr, "  second order: %s (%d free directions, %d active constraints, %.3f s)\n", check->reason.c_str(),
                 check->nullity, check->constraints, check->seconds);
  if (!summary.converged) return 3;
  return failing.empty() ? 0 : 4;
}
