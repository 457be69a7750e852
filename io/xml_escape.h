// kdmesh — text escaped for an XML attribute value (internal to io/: the VTU and XDMF writers).
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once
#include <string>

namespace kdmesh {

/// `s` with & < > " ' written as entities.
inline std::string xml_escape(const std::string& s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

}  // namespace kdmesh
