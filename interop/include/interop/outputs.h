// The command-line outputs of a solve: summary.json (solver summary + validity report),
// motion.json (the Animation in the contract outside tools read), motion.glb (the animated scene
// as glTF), one URDF and one BVH per character, and scene.json (the scene with the solver's state,
// to resume from).
// The set is written all together or not at all (writeSolveOutputs).
#pragma once

#include <string>

#include "solver/animation.h"
#include "solver/augmented_lagrangian.h"
#include "solver/refinement.h"
#include "solver/second_order.h"
#include "solver/validity.h"

namespace spacetime {

// `attempts`: the transcriptions the solve ran on (solveRefined), written as `refinement`;
// `secondOrder`: the second-order check of the motion when it was asked for, as `second_order`.
std::string summaryJson(const SolverSummary& summary, const ValidityReport& validity,
                        const SpacetimeProblem& problem, const std::vector<TranscriptionAttempt>& attempts = {},
                        const SecondOrderCheck* secondOrder = nullptr);
std::string motionJson(const Animation& animation);
// The same motion as one CSV table for spreadsheets: a header row, then one row per frame with
// the time and, per character and dof, `<character>.<dof>.q`, `.qd`, `.qdd`, `.tau`. Characters
// must share the time grid (sampleAnimation guarantees it).
std::string motionCsv(const Animation& animation);

// Whether `dir` can take a solve's outputs: a new directory in a writable one, or an existing
// directory holding only what a solve writes (the outputs replace it as a whole). False with a
// one-line reason otherwise. Creates nothing.
bool checkOutputDirectory(const std::string& dir, std::string* error);

// The scene a solve resumes from for `path` (spacetime-cli --init): a solve's output directory
// or any file a solve wrote into one other than scene.json (motion.json, summary.json, ...) stands
// for that directory's scene.json - those files hold the sampled motion, not the splines'
// coefficients and the multipliers a warm start takes, which the same solve wrote there. A
// directory counts as a solve's output when it holds its summary.json. Any other path is
// returned as it is (a solved scene, an editor save). Empty, with a one-line reason, for a
// directory that is no solve's output or whose scene.json is missing.
std::string resumedScenePath(const std::string& path, std::string* error);

// Frames per second of each motion file. motion.json is for analysis (dense); a BVH at 1000 Hz
// became a 50 s action in Blender's importer with its default settings (one scene frame per BVH
// frame at 24 fps), so BVH gets an animation frame rate (spacetime-cli: the scene's frameRate). glTF's keys are
// cubic with exact tangents on a grid at the same rate plus the splines' knots (gltfKeyTimes):
// within 1e-5 m between keys, where linear keys at 30 Hz missed the lamp's head by 1.9 cm.
struct OutputOptions {
  double motionRate = 1000;  // motion.json
  double bvhRate = 24;       // <character>.bvh (spacetime-cli: the scene's frameRate)
  double gltfRate = 24;      // motion.glb's key grid (the same)
  bool urdfZUp = false;      // the URDF files Z-up (UrdfOptions::zUp)
};

// Writes summary.json, motion.json, motion.glb, scene.json, <character>.urdf and <character>.bvh
// (the motion at the options' rates) as the directory dir, all together or not at all. False with a reason on error.
bool writeSolveOutputs(const SpacetimeProblem& problem, const SolverSummary& summary,
                       const ValidityReport& validity, const OutputOptions& options, const std::string& dir,
                       std::string* error, std::string* warning,
                       const std::vector<TranscriptionAttempt>& attempts = {},
                       const SecondOrderCheck* secondOrder = nullptr);

}  // namespace spacetime
