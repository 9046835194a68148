// Morph blending by camera distance (docs/morphing.md), shared by the report viewer
// (viewer.js, bundled) and examples/viewer/. A level's GLB carries one morph target that
// moves its vertices onto the next coarser level; the farther the camera, the less the
// finer level's detail shows, so the more the level becomes the coarser one: weight 0
// up to `near` times the distance that frames the model, 1 from `far` times it, linear in
// between. A viewer that switches to the coarser level's file at weight 1 switches to
// what is already on screen: no pop.
export const MORPH_NEAR = 1.0;
export const MORPH_FAR = 3.0;

export function morphWeight(distance, framing, near = MORPH_NEAR, far = MORPH_FAR) {
  if (!(framing > 0)) return 0;
  const t = (distance / framing - near) / (far - near);
  return t <= 0 ? 0 : t >= 1 ? 1 : t;
}

// The meshes under `root` that have morph targets.
export function morphMeshes(root) {
  const found = [];
  root.traverse((o) => {
    if (o.isMesh && o.morphTargetInfluences && o.morphTargetInfluences.length) found.push(o);
  });
  return found;
}

export function setMorph(meshes, weight) {
  for (const m of meshes) m.morphTargetInfluences.fill(weight);
}
