// examples/viewer: loads ?glb=URL and blends its morph target by camera distance
// (scripts/viewer/src/morph_blend.js, the rule the HTML report's views follow too).
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { DRACOLoader } from 'three/addons/loaders/DRACOLoader.js';
import { MeshoptDecoder } from 'three/addons/libs/meshopt_decoder.module.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { morphMeshes, morphWeight, setMorph } from 'scanlod/morph_blend.js';

const q = new URLSearchParams(location.search);
const canvas = document.getElementById('c');
const hud = document.getElementById('hud');
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true });
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xf0f0f0);
scene.add(new THREE.HemisphereLight(0xffffff, 0x8c8478, 1.1));
const key = new THREE.DirectionalLight(0xffffff, 2.0);
scene.add(key);
const camera = new THREE.PerspectiveCamera(30, 1, 0.01, 100);
const controls = new OrbitControls(camera, canvas);

const loader = new GLTFLoader();
loader.setMeshoptDecoder(MeshoptDecoder);
const draco = new DRACOLoader();
draco.setDecoderPath('../../scripts/viewer/node_modules/three/examples/jsm/libs/draco/gltf/');
loader.setDRACOLoader(draco);

let meshes = [], center = new THREE.Vector3(), framing = 1;
function draw() {
  const w = canvas.clientWidth, h = canvas.clientHeight;
  renderer.setSize(w, h, false);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
  const pinned = q.get('weight');
  const weight = pinned !== null ? Number(pinned) : morphWeight(camera.position.distanceTo(center), framing);
  setMorph(meshes, weight);
  window.SCANLOD_MORPH = meshes.length ? weight : null;
  hud.textContent = meshes.length ? `morph weight ${weight.toFixed(2)} (zoom out to blend)` : 'no morph target';
  key.position.copy(camera.position);
  renderer.render(scene, camera);
}

loader.load(q.get('glb'), (gltf) => {
  scene.add(gltf.scene);
  meshes = morphMeshes(gltf.scene);
  const sphere = new THREE.Box3().setFromObject(gltf.scene).getBoundingSphere(new THREE.Sphere());
  center = sphere.center;
  framing = sphere.radius / Math.sin((15 * Math.PI) / 180);
  camera.position.copy(center).add(new THREE.Vector3(0, 0, framing * Number(q.get('distance') || 1)));
  camera.near = framing / 100;
  camera.far = framing * 100;
  controls.target.copy(center);
  controls.addEventListener('change', draw);
  controls.update();
  window.addEventListener('resize', draw);
  draw();
  document.title = 'OK';
}, undefined, (e) => { document.title = 'FAIL: ' + e; });
