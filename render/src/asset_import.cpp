#include "lockstep/render/asset_import.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace lockstep::render {

Model ImportAsset(const AssetSpec& spec) {
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(spec.path, aiProcess_Triangulate | aiProcess_PreTransformVertices |
                                                          aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
  if (!scene || !scene->mRootNode) {
    throw std::runtime_error("asset '" + spec.name + "': cannot import " + spec.path + ": " + importer.GetErrorString());
  }
  Model model;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e30), hi = Eigen::Vector3d::Constant(-1e30);
  std::vector<map::Mesh> meshes;
  std::vector<std::array<std::uint8_t, 3>> colours;
  for (unsigned mi = 0; mi < scene->mNumMeshes; ++mi) {
    const aiMesh* am = scene->mMeshes[mi];
    if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    map::Mesh m;
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      const aiVector3D& p = am->mVertices[v];
      // Y-up files: (x, y, z) -> (x, -z, y), a rotation, so the winding is kept.
      Eigen::Vector3d q = spec.y_up ? Eigen::Vector3d(p.x, -p.z, p.y) : Eigen::Vector3d(p.x, p.y, p.z);
      q *= spec.scale;
      lo = lo.cwiseMin(q);
      hi = hi.cwiseMax(q);
      m.AddVertex(q);
    }
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices == 3) m.AddTriangle(face.mIndices[0], face.mIndices[1], face.mIndices[2]);
    }
    aiColor4D d(0.7f, 0.7f, 0.7f, 1.0f);
    if (scene->mMaterials && am->mMaterialIndex < scene->mNumMaterials) {
      scene->mMaterials[am->mMaterialIndex]->Get(AI_MATKEY_COLOR_DIFFUSE, d);
    }
    auto byte = [](float c) { return static_cast<std::uint8_t>(std::lround(std::clamp(c, 0.0f, 1.0f) * 255)); };
    colours.push_back({byte(d.r), byte(d.g), byte(d.b)});
    meshes.push_back(std::move(m));
  }
  if (meshes.empty() || lo.x() > hi.x()) throw std::runtime_error("asset '" + spec.name + "': " + spec.path + " has no triangles");
  const Eigen::Vector3d centre = (lo + hi) / 2;
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    for (std::size_t k = 0; k + 2 < meshes[i].vertices.size(); k += 3) {
      for (int c = 0; c < 3; ++c) meshes[i].vertices[k + c] -= static_cast<float>(centre[c]);
    }
    AppendMesh(&model.vertices, meshes[i], colours[i], kMatPlain, spec.tag);
  }
  model.half_extents = (hi - lo) / 2;
  return model;
}

}  // namespace lockstep::render
