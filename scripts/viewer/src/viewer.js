// The 3D views of scanlod's report pages (OUTPUT/summary.html, OUTPUT/ITEM/index.html).
//
// build.mjs bundles this file, three.js, its GLTFLoader and OrbitControls, the meshopt
// decoder and the Draco decoder (wasm and wrapper embedded) into one classic script, so a
// page works opened from a file (file://: no fetch, no modules, no workers from files) as
// well as served. Nothing is requested from the network: a GLB arrives as a classic
// script NAME.glb.js next to it that stores the file's bytes in base64:
//   (self.SCANLOD_GLB=self.SCANLOD_GLB||{})[document.currentScript.src]="Z2xURg...";
// keyed by its own URL, so any number of items on one page cannot collide.
//
// Page contract (docs/formats.md, "The HTML report"): every <figure class="sl-view"
// data-src="URL of a .glb.js"> holding a <canvas> becomes a view; buttons inside it with
// data-src switch the level shown, loading its GLB script only then. A view loads when it
// comes near the viewport, or with data-load="click" when its canvas or a level button is
// clicked; one load at a time. One view per page is live: when a view is drawn, the one
// live before is released (its scene freed, its canvas back to the thumbnail behind it),
// so a collection page holds one decoded model, not hundreds. A figure's data-state is
// "waiting", "loading", then "drawn" (data-triangles set, data-drawn-ms: milliseconds
// from the page's start to its first draw) or "error"; the tests wait for those. One
// WebGL context serves every view (browsers allow about 16): a view is rendered there and
// copied into its own 2D canvas, again whenever it is orbited. A level whose GLB has a
// morph target (docs/morphing.md) blends into the next coarser level as the camera moves
// away (morph_blend.js); its figure's data-morph says the weight drawn.
import {
  Box3, Color, DirectionalLight, HemisphereLight, PerspectiveCamera, SRGBColorSpace, Scene,
  Sphere, Vector3, WebGLRenderer,
} from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { DRACOLoader } from 'three/examples/jsm/loaders/DRACOLoader.js';
import { MeshoptDecoder } from 'three/examples/jsm/libs/meshopt_decoder.module.js';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import dracoWrapper from 'three/examples/jsm/libs/draco/gltf/draco_wasm_wrapper.js'; // text (build.mjs)
import dracoWasm from 'three/examples/jsm/libs/draco/gltf/draco_decoder.wasm'; // Uint8Array
import { morphMeshes, morphWeight, setMorph } from './morph_blend.js';

// As the PNG thumbnails (docs/glb.md, "Thumbnails"): the same direction about +Y, clay
// where a level has no colours, the same light grey background.
const AZIMUTH = (30 * Math.PI) / 180;
const ELEVATION = (20 * Math.PI) / 180;
const CLAY = [0.78, 0.72, 0.64];
const BACKGROUND = 0.94;
const FOV = 30;

// DRACOLoader fetch()es its decoder from a path; hand it the embedded copies instead. It
// then runs the decoder in a worker made from a Blob URL, which file:// pages allow.
class EmbeddedDRACOLoader extends DRACOLoader {
  _loadLibrary(url, type) {
    if (type === 'text') return Promise.resolve(dracoWrapper);
    const b = dracoWasm;
    return Promise.resolve(b.buffer.slice(b.byteOffset, b.byteOffset + b.byteLength));
  }
}

let loader = null;
function gltfLoader() {
  if (!loader) {
    const draco = new EmbeddedDRACOLoader();
    draco.setDecoderPath('embedded/');
    loader = new GLTFLoader();
    loader.setDRACOLoader(draco);
    loader.setMeshoptDecoder(MeshoptDecoder);
  }
  return loader;
}

let renderer = null;
function sharedRenderer() {
  if (!renderer) {
    renderer = new WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    renderer.outputColorSpace = SRGBColorSpace;
  }
  return renderer;
}

// The GLB bytes behind a .glb.js URL: the script stores them under its own URL.
function loadScript(url) {
  return new Promise((resolve, reject) => {
    const s = document.createElement('script');
    s.src = url;
    s.onload = () => {
      const store = self.SCANLOD_GLB || {};
      const b64 = store[s.src];
      delete store[s.src];
      s.remove();
      if (typeof b64 !== 'string') reject(new Error(url + ' holds no GLB'));
      else resolve(b64);
    };
    s.onerror = () => { s.remove(); reject(new Error('cannot load ' + url)); };
    document.head.appendChild(s);
  });
}

function decodeBase64(b64) {
  const s = atob(b64);
  const u = new Uint8Array(s.length);
  for (let i = 0; i < s.length; i++) u[i] = s.charCodeAt(i);
  return u.buffer;
}

function parseGlb(buffer) {
  return new Promise((resolve, reject) => gltfLoader().parse(buffer, '', resolve, reject));
}

function countTriangles(root) {
  let n = 0;
  root.traverse((o) => {
    if (o.isMesh) {
      const g = o.geometry;
      n += (g.index ? g.index.count : g.attributes.position.count) / 3;
    }
  });
  return n;
}

function disposeScene(scene) {
  scene.traverse((o) => {
    if (o.geometry) o.geometry.dispose();
    if (o.material) o.material.dispose();
  });
}

class View {
  constructor(figure) {
    this.figure = figure;
    this.canvas = figure.querySelector('canvas');
    this.camera = new PerspectiveCamera(FOV, 1, 0.01, 100);
    this.scene = null;
    this.controls = null;
    this.morphs = [];
    this.key = new DirectionalLight(0xffffff, 2.2);
    this.src = figure.dataset.src;
    for (const b of figure.querySelectorAll('button[data-src]')) {
      b.addEventListener('click', () => {
        for (const o of figure.querySelectorAll('button[data-src]')) o.classList.toggle('on', o === b);
        this.src = b.dataset.src;
        enqueue(this);
      });
    }
  }

  async load() {
    const src = this.src;
    if (this.shown === src) return;
    this.figure.dataset.state = 'loading';
    try {
      const gltf = await parseGlb(decodeBase64(await loadScript(src)));
      if (live && live !== this) live.release();
      live = this;
      this.show(gltf.scene);
      this.shown = src;
      this.figure.dataset.triangles = String(countTriangles(gltf.scene));
      if (!this.figure.dataset.drawnMs)
        this.figure.dataset.drawnMs = String(Math.round(performance.now()));
      this.figure.dataset.state = 'drawn';
    } catch (e) {
      this.figure.dataset.state = 'error';
      const why = document.createElement('p');
      why.className = 'sl-error';
      why.textContent = 'cannot show ' + src + ': ' + (e && e.message ? e.message : e);
      this.figure.appendChild(why);
      console.error('scanlod viewer: ' + why.textContent);
    }
  }

  // Back to the thumbnail: the scene freed, the canvas cleared (its CSS background shows).
  release() {
    if (this.scene) disposeScene(this.scene);
    this.scene = null;
    this.shown = null;
    this.morphs = [];
    this.canvas.getContext('2d').clearRect(0, 0, this.canvas.width, this.canvas.height);
    delete this.figure.dataset.triangles;
    delete this.figure.dataset.morph;
    this.figure.dataset.state = 'waiting';
  }

  show(root) {
    root.traverse((o) => {
      if (o.isMesh && !o.geometry.attributes.color && o.material && o.material.color)
        o.material.color.setRGB(CLAY[0], CLAY[1], CLAY[2], SRGBColorSpace);
    });
    if (this.scene) disposeScene(this.scene);
    const scene = new Scene();
    scene.background = new Color().setRGB(BACKGROUND, BACKGROUND, BACKGROUND, SRGBColorSpace);
    scene.add(new HemisphereLight(0xffffff, 0x8c8478, 1.1));
    scene.add(this.key, this.key.target);
    scene.add(root);
    this.scene = scene;

    const sphere = new Box3().setFromObject(root).getBoundingSphere(new Sphere());
    const r = sphere.radius > 0 ? sphere.radius : 1;
    const back = new Vector3(Math.cos(ELEVATION) * Math.sin(AZIMUTH), Math.sin(ELEVATION),
                             Math.cos(ELEVATION) * Math.cos(AZIMUTH));
    const distance = (r / Math.sin(((FOV / 2) * Math.PI) / 180)) * 0.92;
    this.camera.position.copy(sphere.center).addScaledVector(back, distance);
    this.camera.near = distance / 100;
    this.camera.far = distance * 100;
    this.camera.lookAt(sphere.center);
    this.camera.updateProjectionMatrix();
    if (!this.controls) {
      this.controls = new OrbitControls(this.camera, this.canvas);
      this.controls.addEventListener('change', () => this.draw());
    }
    this.center = sphere.center.clone();
    this.framing = distance;
    this.morphs = morphMeshes(root);
    if (!this.morphs.length) delete this.figure.dataset.morph; // the level before had one
    this.controls.target.copy(sphere.center);
    this.controls.update(); // may draw ('change')
    this.draw();
  }

  // Renders in the shared context and copies the picture into this view's canvas.
  draw() {
    if (!this.scene) return;
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(this.canvas.clientWidth * dpr));
    const h = Math.max(1, Math.round(this.canvas.clientHeight * dpr));
    if (this.canvas.width !== w || this.canvas.height !== h) {
      this.canvas.width = w;
      this.canvas.height = h;
    }
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    // The key light above-left of the camera, following it as it orbits.
    const offset = new Vector3(-0.6, 0.7, 0.45).applyQuaternion(this.camera.quaternion);
    this.key.target.position.copy(this.center);
    this.key.position.copy(this.center).add(offset);
    if (this.morphs.length) {
      const w = morphWeight(this.camera.position.distanceTo(this.center), this.framing);
      setMorph(this.morphs, w);
      this.figure.dataset.morph = w.toFixed(3);
    }
    const gl = sharedRenderer();
    gl.setPixelRatio(1);
    gl.setSize(w, h, false);
    gl.render(this.scene, this.camera);
    this.canvas.getContext('2d').drawImage(gl.domElement, 0, 0);
  }
}

// One load at a time: a collection page must not decode every item at once; one view live.
let queue = Promise.resolve();
let live = null;
function enqueue(view) {
  queue = queue.then(() => view.load());
  return queue;
}

export function start(root = document) {
  const views = [...root.querySelectorAll('figure.sl-view[data-src]')]
    .filter((f) => f.querySelector('canvas'))
    .map((f) => new View(f));
  for (const v of views) v.figure.dataset.state = 'waiting';
  // Click-to-load views: the canvas is the button until its model is live (then a click
  // or drag turns it).
  const onClick = views.filter((v) => v.figure.dataset.load === 'click');
  for (const v of onClick)
    v.canvas.addEventListener('click', () => { if (!v.scene) enqueue(v); });
  const auto = views.filter((v) => v.figure.dataset.load !== 'click');
  if (!('IntersectionObserver' in self)) {
    auto.forEach(enqueue);
    return views.length;
  }
  const seen = new IntersectionObserver((entries) => {
    for (const e of entries) {
      if (!e.isIntersecting) continue;
      seen.unobserve(e.target);
      enqueue(e.target.slViewer);
    }
  }, { rootMargin: '300px' });
  for (const v of auto) {
    v.figure.slViewer = v;
    seen.observe(v.figure);
  }
  return views.length;
}

if (document.readyState === 'loading') document.addEventListener('DOMContentLoaded', () => start());
else start();
