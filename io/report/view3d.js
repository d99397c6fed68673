// tolver verify: the report's interactive 3D view (three.js r111 and its OrbitControls, inline).
// The data are in <script type="application/json" id="tolver-view-data">, written by
// io/report/view3d.cpp: per vertex of the decimated surface (each an original surface sample)
// its position and normal (mm, part frame), its colour on the maps' discrete scale, its total,
// program and machine deviations (um, + material left), flags, zone, CAD face, state and CL line.
// window.tolverView holds the scene and the functions a script may call (pickAt, setView,
// showFace, render).
(function () {
  'use strict';
  function init() {
    const holder = document.getElementById('tolver-view');
    const dataNode = document.getElementById('tolver-view-data');
    if (!holder || !dataNode) return;
    const D = JSON.parse(dataNode.textContent);

    function bytes(b64) {
      const s = atob(b64);
      const out = new Uint8Array(s.length);
      for (let i = 0; i < s.length; ++i) out[i] = s.charCodeAt(i);
      return out.buffer;
    }
    const P = new Float32Array(bytes(D.positions));
    const N = new Float32Array(bytes(D.normals));
    const C = new Uint8Array(bytes(D.colours));
    const TOTAL = new Float32Array(bytes(D.total_um));
    const PROGRAM = new Float32Array(bytes(D.program_um));
    const MACHINE = new Float32Array(bytes(D.machine_um));
    const FLAGS = new Uint8Array(bytes(D.flags));
    const SAMPLE = new Uint32Array(bytes(D.sample));
    const ZONE = new Int32Array(bytes(D.zone));
    const GROUP = new Int32Array(bytes(D.group));
    const STATE = new Uint8Array(bytes(D.state));
    const LINE = new Uint32Array(bytes(D.cl_line));
    const FACES = new Uint32Array(bytes(D.faces));
    const V = P.length / 3;
    const MACHINED = 1, SPLIT = 2, BEYOND = 4, OUT = 8;

    const canvas = holder.querySelector('canvas');
    const info = document.getElementById('tolver-pick');
    let renderer;
    try {
      renderer = new THREE.WebGLRenderer({canvas: canvas, antialias: true,
                                          preserveDrawingBuffer: true});
    } catch (e) {
      holder.querySelector('.tv-msg').textContent =
          'This browser cannot draw WebGL: the 3D view is not shown; the maps below show the same ' +
          'deviations.';
      return;
    }
    renderer.setPixelRatio(1);
    renderer.setClearColor(0xffffff, 1);
    const scene = new THREE.Scene();
    const centre = new THREE.Vector3(D.centre[0], D.centre[1], D.centre[2]);
    const radius = D.radius;
    const camera = new THREE.OrthographicCamera(-1, 1, 1, -1, -100 * radius, 100 * radius);
    const controls = new THREE.OrbitControls(camera, canvas);
    controls.enableDamping = false;
    controls.screenSpacePanning = true;
    scene.add(new THREE.AmbientLight(0xffffff, 0.45));
    const light = new THREE.DirectionalLight(0xffffff, 0.6);
    camera.add(light);
    light.position.set(0.3, 0.5, 1);
    scene.add(camera);

    // Positions relative to the centre (float precision), the predicted one moved along the
    // normal by the exaggerated total deviation.
    const nominalPos = new Float32Array(3 * V), predictedPos = new Float32Array(3 * V);
    for (let i = 0; i < V; ++i)
      for (let k = 0; k < 3; ++k) nominalPos[3 * i + k] = P[3 * i + k] - D.centre[k];
    function indexOf(list) {
      const a = new Uint32Array(list.length);
      a.set(list);
      return new THREE.BufferAttribute(a, 1);
    }
    const predictedGeo = new THREE.BufferGeometry();
    predictedGeo.setAttribute('position', new THREE.BufferAttribute(predictedPos, 3));
    predictedGeo.setAttribute('normal', new THREE.BufferAttribute(N, 3));
    predictedGeo.setAttribute('color', new THREE.BufferAttribute(C, 3, true));
    predictedGeo.setIndex(new THREE.BufferAttribute(FACES, 1));
    const nominalGeo = new THREE.BufferGeometry();
    nominalGeo.setAttribute('position', new THREE.BufferAttribute(nominalPos, 3));
    nominalGeo.setAttribute('normal', new THREE.BufferAttribute(N, 3));
    nominalGeo.setIndex(new THREE.BufferAttribute(FACES, 1));
    // The faces with a vertex out of tolerance, drawn as a wire over the predicted surface.
    const outList = [];
    for (let f = 0; f < FACES.length; f += 3)
      if ((FLAGS[FACES[f]] | FLAGS[FACES[f + 1]] | FLAGS[FACES[f + 2]]) & OUT)
        outList.push(FACES[f], FACES[f + 1], FACES[f + 2]);
    const outGeo = new THREE.BufferGeometry();
    outGeo.setAttribute('position', predictedGeo.getAttribute('position'));
    outGeo.setIndex(indexOf(outList));

    const shaded = new THREE.MeshLambertMaterial({vertexColors: THREE.VertexColors,
                                                  side: THREE.DoubleSide});
    const flat = new THREE.MeshBasicMaterial({vertexColors: THREE.VertexColors,
                                              side: THREE.DoubleSide});
    const predicted = new THREE.Mesh(predictedGeo, shaded);
    const nominal = new THREE.Mesh(nominalGeo, new THREE.MeshLambertMaterial({
      color: 0x9aa3ad, transparent: true, opacity: 0.35, side: THREE.DoubleSide,
      depthWrite: false}));
    nominal.visible = false;
    const outMesh = new THREE.Mesh(outGeo, new THREE.MeshBasicMaterial({
      color: 0x111111, wireframe: true, polygonOffset: true, polygonOffsetFactor: -1}));
    const highlight = new THREE.Mesh(new THREE.BufferGeometry(), new THREE.MeshBasicMaterial({
      color: 0xff00ff, wireframe: true}));
    highlight.visible = false;
    highlight.geometry.setAttribute('position', predictedGeo.getAttribute('position'));
    const marker = new THREE.Mesh(new THREE.SphereBufferGeometry(radius * 0.012, 12, 8),
                                  new THREE.MeshBasicMaterial({color: 0x000000}));
    marker.visible = false;
    scene.add(predicted, nominal, outMesh, highlight, marker);

    let exaggeration = D.exaggeration;
    function place() {
      const s = exaggeration * 1e-3;  // um to mm, times the factor
      for (let i = 0; i < V; ++i) {
        const d = (FLAGS[i] & MACHINED) && !(FLAGS[i] & BEYOND) ? TOTAL[i] * s : 0;
        for (let k = 0; k < 3; ++k)
          predictedPos[3 * i + k] = nominalPos[3 * i + k] + N[3 * i + k] * d;
      }
      predictedGeo.getAttribute('position').needsUpdate = true;
      predictedGeo.computeBoundingSphere();
      predictedGeo.boundingBox = null;
    }
    place();

    function resize() {
      const w = canvas.clientWidth || 800, h = canvas.clientHeight || 600;
      renderer.setSize(w, h, false);
      const aspect = w / h, r = radius * 1.1;
      camera.left = -r * Math.max(aspect, 1);
      camera.right = r * Math.max(aspect, 1);
      camera.top = r / Math.min(aspect, 1);
      camera.bottom = -r / Math.min(aspect, 1);
      camera.updateProjectionMatrix();
    }
    const labels = [];
    for (const g of D.regions) {
      const el = document.createElement('div');
      el.className = 'tv-label';
      el.textContent = g.label;
      el.title = g.text;
      holder.appendChild(el);
      labels.push({el: el, at: new THREE.Vector3(g.where[0], g.where[1], g.where[2]).sub(centre)});
    }
    function render() {
      renderer.render(scene, camera);
      const w = canvas.clientWidth, h = canvas.clientHeight;
      for (const l of labels) {
        const v = l.at.clone().project(camera);
        l.el.style.left = (canvas.offsetLeft + (v.x + 1) / 2 * w) + 'px';
        l.el.style.top = (canvas.offsetTop + (1 - v.y) / 2 * h) + 'px';
      }
    }
    controls.addEventListener('change', render);
    window.addEventListener('resize', function () { resize(); render(); });

    function setView(name) {
      const view = D.views.find(function (v) { return v.name === name; }) || D.views[0];
      const dir = new THREE.Vector3(view.direction[0], view.direction[1], view.direction[2])
                      .normalize();
      camera.up.set(view.up[0], view.up[1], view.up[2]);
      camera.position.copy(dir.clone().multiplyScalar(-4 * radius));
      camera.zoom = 1;
      controls.target.set(0, 0, 0);
      camera.lookAt(controls.target);
      camera.updateProjectionMatrix();
      controls.update();
      render();
    }

    function um(x) { return (x >= 0 ? '+' : '\u2212') + Math.abs(x).toFixed(2) + ' \u00b5m'; }
    function show(i) {
      const p = [P[3 * i], P[3 * i + 1], P[3 * i + 2]];
      const f = FLAGS[i], z = ZONE[i], g = GROUP[i];
      const rows = [['sample', String(SAMPLE[i])],
                    ['at (mm)', '(' + p.map(function (x) { return x.toFixed(3); }).join(', ') +
                                    ')']];
      if (!(f & MACHINED)) {
        rows.push(['total', 'not machined by this program']);
      } else {
        rows.push(['total', f & BEYOND ? 'beyond the gouge search range' : um(TOTAL[i])]);
        rows.push(['program', f & SPLIT ? um(PROGRAM[i]) : 'does not split here']);
        rows.push(['machine', f & SPLIT ? um(MACHINE[i]) : 'does not split here']);
      }
      rows.push(['state', D.states[STATE[i]]]);
      if (z >= 0) {
        const zone = D.zones[z];
        rows.push(['zone', zone.region + ' [' + zone.lower_um.toFixed(1) + ', ' +
                               zone.upper_um.toFixed(1) + '] \u00b5m']);
      }
      rows.push(['CAD face', D.groups[g]]);
      rows.push(['CL line', LINE[i] > 0 ? String(LINE[i]) : '\u2014']);
      info.innerHTML = '';
      const table = document.createElement('table');
      for (const r of rows) {
        const tr = table.insertRow();
        const th = document.createElement('th');
        th.textContent = r[0];
        tr.appendChild(th);
        const td = tr.insertCell();
        if (r[0] === 'CAD face' && document.getElementById('region-' + D.group_ids[g])) {
          const a = document.createElement('a');
          a.href = '#region-' + D.group_ids[g];
          a.textContent = r[1];
          td.appendChild(a);
        } else {
          td.textContent = r[1];
        }
      }
      info.appendChild(table);
      info.dataset.sample = SAMPLE[i];
      info.dataset.total = (f & MACHINED) && !(f & BEYOND) ? TOTAL[i] : '';
      info.dataset.program = (f & MACHINED) && (f & SPLIT) ? PROGRAM[i] : '';
      info.dataset.machine = (f & MACHINED) && (f & SPLIT) ? MACHINE[i] : '';
      info.dataset.line = LINE[i];
      info.dataset.face = D.groups[g];
      marker.position.set(predictedPos[3 * i], predictedPos[3 * i + 1], predictedPos[3 * i + 2]);
      marker.visible = true;
      render();
    }

    const raycaster = new THREE.Raycaster();
    // The sample under a point of the window (client pixels): the vertex of the hit triangle
    // nearest the hit; null when the ray meets no shown surface.
    function pickAt(x, y) {
      const rect = canvas.getBoundingClientRect();
      const ndc = new THREE.Vector2((x - rect.left) / rect.width * 2 - 1,
                                    -(y - rect.top) / rect.height * 2 + 1);
      raycaster.setFromCamera(ndc, camera);
      const targets = [predicted, nominal].filter(function (m) { return m.visible; });
      const hits = raycaster.intersectObjects(targets);
      if (!hits.length) {
        info.textContent = 'no surface under the pointer';
        for (const k of ['sample', 'total', 'program', 'machine', 'line', 'face'])
          delete info.dataset[k];
        marker.visible = false;
        render();
        return null;
      }
      const h = hits[0], pos = h.object.geometry.getAttribute('position').array;
      let best = -1, bestD = Infinity;
      for (const v of [h.face.a, h.face.b, h.face.c]) {
        const dx = pos[3 * v] - h.point.x, dy = pos[3 * v + 1] - h.point.y,
              dz = pos[3 * v + 2] - h.point.z;
        const d = dx * dx + dy * dy + dz * dz;
        if (d < bestD) { bestD = d; best = v; }
      }
      show(best);
      return best;
    }
    let down = null;
    canvas.addEventListener('pointerdown', function (e) { down = [e.clientX, e.clientY]; });
    canvas.addEventListener('pointerup', function (e) {
      if (down && Math.hypot(e.clientX - down[0], e.clientY - down[1]) < 4)
        pickAt(e.clientX, e.clientY);
      down = null;
    });

    // A CAD face: its faces outlined, seen along its mean normal.
    function showFace(g) {
      const list = [];
      const n = new THREE.Vector3();
      for (let f = 0; f < FACES.length; f += 3)
        if (GROUP[FACES[f]] === g && GROUP[FACES[f + 1]] === g && GROUP[FACES[f + 2]] === g)
          list.push(FACES[f], FACES[f + 1], FACES[f + 2]);
      for (let i = 0; i < V; ++i)
        if (GROUP[i] === g) n.add(new THREE.Vector3(N[3 * i], N[3 * i + 1], N[3 * i + 2]));
      highlight.geometry.setIndex(indexOf(list));
      highlight.visible = list.length > 0;
      if (n.lengthSq() > 1e-12) {
        n.normalize();
        D.views.push({name: 'face', direction: [-n.x, -n.y, -n.z],
                      up: Math.abs(n.z) > 0.9 ? [0, 1, 0] : [0, 0, 1]});
        setView('face');
        D.views.pop();
      }
      holder.scrollIntoView();
      render();
    }

    // Controls.
    function on(id, event, f) { document.getElementById(id).addEventListener(event, f); }
    on('tv-predicted', 'change', function (e) { predicted.visible = e.target.checked; render(); });
    on('tv-nominal', 'change', function (e) { nominal.visible = e.target.checked; render(); });
    on('tv-out', 'change', function (e) { outMesh.visible = e.target.checked; render(); });
    on('tv-shading', 'change', function (e) {
      predicted.material = e.target.checked ? shaded : flat;
      render();
    });
    on('tv-exaggeration', 'change', function (e) {
      const x = parseFloat(e.target.value);
      exaggeration = isFinite(x) && x >= 0 ? x : D.exaggeration;
      place();
      render();
    });
    for (const b of holder.querySelectorAll('button[data-view]'))
      b.addEventListener('click', function () { setView(b.dataset.view); });
    document.addEventListener('click', function (e) {
      const a = e.target.closest && e.target.closest('a[data-face]');
      if (!a) return;
      e.preventDefault();
      showFace(parseInt(a.dataset.face, 10));
    });
    if (location.hash === '#view3d') document.body.classList.add('tv-full');

    resize();
    setView(D.views[0].name);
    window.tolverView = {scene: scene, camera: camera, renderer: renderer, canvas: canvas,
                         predicted: predicted, nominal: nominal, out: outMesh, highlight: highlight,
                         vertices: V,
                         sample: SAMPLE, centre: centre, pickAt: pickAt, setView: setView,
                         showFace: showFace, show: show, render: render};
  }
  // The CAD faces table comes after the view: wait for the whole document.
  if (document.readyState === 'loading')
    document.addEventListener('DOMContentLoaded', init);
  else
    init();
})();
