// Bulk removal of a set of faces with the edges and nodes they leave behind
// (the sketch cut removes half a mesh at once). The primitives of
// storage/model.h keep every node ring sorted and linked after each call,
// which is wasted work on the rings of nodes that die in the same batch;
// this removes everything in one pass per kind and maintains only the rings
// of nodes that survive.
#pragma once

#include <atelier/storage/model.h>

#include <span>

namespace atelier {

/// Removes `faces`, then `edges`, then `nodes`, leaving the same tables
/// (live rows, free lists, generations) as delete_face, delete_edge and
/// delete_node called in that order. Reads and writes: nodes, edges,
/// halfedges and faces (rows and slots); topology_version.
/// Preconditions (the caller checks them; they are asserted in debug
/// builds): no ring node sits in a face of `faces`; every edge of `edges` is
/// faceless once `faces` are gone and held by no mesh edge; every node of
/// `nodes` has all its edges in `edges`. Lists hold no repeats.
void remove_faces_bulk(Model& model, std::span<const FaceIdx> faces, std::span<const EdgeIdx> edges,
                       std::span<const NodeIdx> nodes);

}  // namespace atelier
