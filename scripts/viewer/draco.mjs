// Rewrites a GLB with KHR_draco_mesh_compression (glTF-Transform's writer with Google's
// Draco encoder, edgebreaker, its default quantisation): the viewer's test makes Draco
// files from scanlod's plain GLBs with it (tests/export/test_html_report.sh).
//   node scripts/viewer/draco.mjs IN.glb OUT.glb
import { NodeIO } from '@gltf-transform/core';
import { KHRDracoMeshCompression } from '@gltf-transform/extensions';
import draco3d from 'draco3dgltf';

const [input, output] = process.argv.slice(2);
if (!input || !output) {
  console.error('usage: draco.mjs IN.glb OUT.glb');
  process.exit(2);
}
const io = new NodeIO().registerExtensions([KHRDracoMeshCompression]).registerDependencies({
  'draco3d.encoder': await draco3d.createEncoderModule(),
  'draco3d.decoder': await draco3d.createDecoderModule(),
});
const doc = await io.read(input);
doc.createExtension(KHRDracoMeshCompression).setRequired(true)
  .setEncoderOptions({ method: KHRDracoMeshCompression.EncoderMethod.EDGEBREAKER });
await io.write(output, doc);
