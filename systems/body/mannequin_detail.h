// Internals shared by the sources of the mannequin (systems/body/mannequin.h):
//
//   mannequin_topology.cpp  rings, faces, feature curves and points
//   mannequin.cpp           parameters, positions, the reference body
//   mannequin_sampling.cpp  random body measurements
#pragma once

namespace atelier::mannequin_detail {

// Torso key levels (ring index of each is fixed by the resolution).
enum TorsoKey { kTCrotch, kTHip, kTWaist, kTUnderbust, kTBust, kTArmpit, kTShoulder, kTNeckBase, kTNeckTop, kTKeys };
enum LegKey { kLCrotch, kLThigh, kLKnee, kLAnkle, kLKeys };

}  // namespace atelier::mannequin_detail
