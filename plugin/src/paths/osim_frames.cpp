#include "osim_frames.hpp"

#include <algorithm>

#include "../io/opensim_text.hpp"

namespace flatsos::plugin::osim_xml {

FrameTable::FrameTable(const Reader& reader, Element& model) : reader_(reader) {
  Element ground = model.getOptionalElement("Ground");
  if (ground.isValid()) frame_elements_.push_back({FramePose{"ground", Eigen::Isometry3d::Identity()}, ground});
  if (Element list = set_objects(model, "BodySet"); list.isValid())
    for (auto it = list.element_begin("Body"); it != list.element_end(); ++it) {
      Element body = *it;
      const std::string name = body.getOptionalAttributeValue("name", "");
      if (name.empty()) reader_.fail("BodySet", "a Body without a name");
      if (name != "ground") bodies_.push_back(name);
      frame_elements_.push_back({FramePose{name, Eigen::Isometry3d::Identity()}, body});
      if (Element components = body.getOptionalElement("components"); components.isValid())
        read_offsets(components, "/bodyset/" + name);
    }
  if (Element components = model.getOptionalElement("components"); components.isValid()) read_offsets(components, "");
  if (Element list = set_objects(model, "JointSet"); list.isValid())
    for (auto it = list.element_begin(); it != list.element_end(); ++it) {
      Element joint = *it;
      if (Element frames = joint.getOptionalElement("frames"); frames.isValid())
        read_offsets(frames, "/jointset/" + joint.getOptionalAttributeValue("name", ""));
    }
  // Offset frames may hold wrap objects too: with their poses, now that all are known.
  std::vector<std::pair<FramePose, Element>> offset_elements;
  for (auto& [pose, element] : frame_elements_) {
    if (element.getElementTag() != "PhysicalOffsetFrame") continue;
    offset_elements.push_back({resolve(pose.body, "PhysicalOffsetFrame '" + pose.body + "'"), element});
  }
  frame_elements_.erase(std::remove_if(frame_elements_.begin(), frame_elements_.end(),
                                       [](auto& entry) { return entry.second.getElementTag() == "PhysicalOffsetFrame"; }),
                        frame_elements_.end());
  frame_elements_.insert(frame_elements_.end(), offset_elements.begin(), offset_elements.end());
}

void FrameTable::read_offsets(Element& list, const std::string& owner_path) {
  for (auto it = list.element_begin("PhysicalOffsetFrame"); it != list.element_end(); ++it) {
    Element f = *it;
    OffsetFrame frame;
    frame.name = f.getOptionalAttributeValue("name", "");
    frame.path = owner_path + "/" + frame.name;
    const std::string where = "PhysicalOffsetFrame '" + frame.path + "'";
    frame.parent_socket = reader_.text(f, "socket_parent");
    if (frame.parent_socket.empty()) reader_.fail(where, "missing <socket_parent>");
    frame.offset.translation() = reader_.vec3_or(f, "translation", where, Eigen::Vector3d::Zero());
    frame.offset.linear() = body_fixed_xyz(reader_.vec3_or(f, "orientation", where, Eigen::Vector3d::Zero()));
    offsets_.push_back(frame);
    // Remembered by path; its pose is resolved once every frame is known.
    frame_elements_.push_back({FramePose{frame.path, Eigen::Isometry3d::Identity()}, f});
  }
}

FramePose FrameTable::resolve(const std::string& socket, const std::string& where) const {
  return resolve_at_depth(socket, where, 0);
}

FramePose FrameTable::resolve_at_depth(const std::string& socket, const std::string& where, int depth) const {
  if (depth > 16) reader_.fail(where, "frame '" + socket + "' is an offset of itself");
  const std::string name = opensim_text::last_component(socket);
  if (name == "ground") return {"ground", Eigen::Isometry3d::Identity()};
  const bool is_body = std::find(bodies_.begin(), bodies_.end(), name) != bodies_.end();
  if (is_body && (socket.find("/bodyset/") != std::string::npos || socket.find('/') == std::string::npos))
    return {name, Eigen::Isometry3d::Identity()};
  const OffsetFrame* match = nullptr;
  int same_name = 0;
  for (const OffsetFrame& f : offsets_) {
    if (f.path == socket) {
      match = &f;
      same_name = 1;
      break;
    }
    if (f.name == name) match = &f, ++same_name;
  }
  if (same_name > 1) reader_.fail(where, "frame '" + socket + "' matches " + std::to_string(same_name) + " PhysicalOffsetFrames");
  if (match) {
    FramePose parent = resolve_at_depth(match->parent_socket, where, depth + 1);
    parent.in_body = parent.in_body * match->offset;
    return parent;
  }
  if (is_body) return {name, Eigen::Isometry3d::Identity()};
  reader_.fail(where, "frame '" + socket + "' is neither ground, a body nor a PhysicalOffsetFrame");
}

}  // namespace flatsos::plugin::osim_xml
