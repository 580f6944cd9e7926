#pragma once
// Where an .osim document's physical frames are: ground, the bodies, and PhysicalOffsetFrames
// (a joint's <frames>, the model's or a body's <components>), each as a body and a pose in it.
// OpenSim 3 (bodies only) and 4 documents.

#include <string>
#include <utility>
#include <vector>

#include "osim_xml.hpp"

namespace flatsos::plugin::osim_xml {

struct FramePose {
  std::string body;  ///< "ground" or a body name
  Eigen::Isometry3d in_body = Eigen::Isometry3d::Identity();
};

class FrameTable {
 public:
  /// Reads the bodies and offset frames of <Model> `model`.
  FrameTable(const Reader& reader, Element& model);

  /// Resolves a socket path ("/bodyset/r_humerus", "/ground", "r_humerus",
  /// "/jointset/elbow/r_ulna_offset", ...). Throws OpenSimFileError at `where` when the frame
  /// is neither ground, a body nor a unique offset frame.
  FramePose resolve(const std::string& socket, const std::string& where) const;

  const std::vector<std::string>& bodies() const { return bodies_; }
  /// Every body element (with its name) and every offset frame element (with its pose), for
  /// reading the wrap objects they hold.
  const std::vector<std::pair<FramePose, Element>>& frameElements() const { return frame_elements_; }

 private:
  struct OffsetFrame {
    std::string name, path, parent_socket;
    Eigen::Isometry3d offset = Eigen::Isometry3d::Identity();
  };
  const Reader& reader_;
  std::vector<std::string> bodies_;
  std::vector<OffsetFrame> offsets_;
  std::vector<std::pair<FramePose, Element>> frame_elements_;

  void read_offsets(Element& list, const std::string& owner_path);
  FramePose resolve_at_depth(const std::string& socket, const std::string& where, int depth) const;
};

}  // namespace flatsos::plugin::osim_xml
