// Diffuse lighting for a 3D view that the CPU draws (SwiftShader, llvmpipe: a browser without a GPU).
// meshcat gives every mesh a Phong material, lit per pixel by its five lights; once the kitchen's room fills
// the view, that lighting is most of a software frame. A Lambert material with the same colour, texture and
// transparency draws the same scene about four times cheaper (scripts/bench_viewer_frame.py), without the
// specular highlights. Used by the page (app.js) and by the benchmark, so both measure the same thing.
const diffuseOf = new WeakMap();  // Phong material -> its Lambert twin, made once

function diffuseOnly(scene, THREE) {
  // swap every Phong material under ``scene`` for its Lambert twin (new meshes arrive at any time: call per frame)
  scene.traverse((node) => {
    const material = node.material;
    if (!material || material.type !== "MeshPhongMaterial") { return; }
    let twin = diffuseOf.get(material);
    if (!twin) {
      twin = new THREE.MeshLambertMaterial().copy(material);
      diffuseOf.set(material, twin);
    }
    node.material = twin;
  });
}
