// kdmesh — Abaqus / CalculiX .inp writer for FeMesh (mesh part of an input deck).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <cstdint>
#include <string>

#include "core/fe_mesh.h"

namespace kdmesh {

struct InpOptions {
  std::string heading = "kdmesh";  ///< the *HEADING line (one line, no line breaks)
  std::string all_elset = "EALL";  ///< name of the ELSET holding every tet
  std::string all_nset = "NALL";   ///< name of the NSET holding every node
};

/// Writes the mesh part of an Abaqus / CalculiX input deck, atomically:
///   *HEADING
///   *NODE, NSET=NALL                       node n = point id + 1
///   *ELEMENT, TYPE=C3D4|C3D10, ELSET=EALL  element t = tet index + 1 (FeMesh's node order is
///                                          Abaqus's for both types)
///   per group of dim 3:  *ELSET (its tets) and *NSET (their nodes)
///   per group of dim 2:  *NSET (nodes of its faces) and *SURFACE, TYPE=ELEMENT: one
///                        "tet, S<k>" line per face (the tet face with the same corners)
///   per group of dim 1:  *NSET (nodes of its edges)
/// Sets list ascending ids, 16 per line. Faces and edges are not written as elements.
///
/// Abaqus / CalculiX face labels of C3D4 and C3D10 (corner nodes, 1-based): S1 = (1,2,3),
/// S2 = (1,4,2), S3 = (2,4,3), S4 = (3,4,1). A face is matched to its tet by its sorted corner
/// triple; when two tets share it (an interface), the one the face's normal points out of is
/// taken (the face's corners appear in that tet's face in the reverse cyclic order).
///
/// Coordinates are written with the shortest round-trip digits when they fit in 20 characters
/// (CalculiX reads only the first 20 characters of a field) and with as many significant digits
/// as fit otherwise (at least 12). No data line exceeds 80 characters or 16 entries: a C3D10
/// element is written as "id, 5 nodes," and a continuation line with the other 5 nodes.
///
/// Group names are used as set names. Because Abaqus names are case-insensitive and a group of
/// each dimension gets an NSET, names must be unique ignoring case over all groups, at most 80
/// characters, and must not equal the all-tets ELSET or all-nodes NSET name (case-insensitively).
/// Throws UsageError for an invalid mesh (see index_fe_mesh) or names, and for a group face
/// that is not a face of any tet (naming the face, its corners and its group); OutputError
/// if the file cannot be written.
void write_inp(const FeMesh& mesh, const std::string& path, const InpOptions& options = {});

/// Abaqus face label (1..4) of the tet face with corners {a, b, c} among the tet's corners
/// `tet[0..3]`, or 0 if the three are not all corners of it.
int abaqus_face_label(const std::uint32_t* tet, std::uint32_t a, std::uint32_t b, std::uint32_t c);

}  // namespace kdmesh
