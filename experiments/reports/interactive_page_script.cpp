// CSS and JavaScript of the interactive page (see interactive_page_script.h). Plain ES2017 on the
// global THREE of libjs-three r111 (three.min.js + examples/js/controls/OrbitControls.js).
#include "experiments/reports/interactive_page_script.h"

namespace quadrix {

const char* const kPageStyle = R"CSS(
html, body { margin: 0; height: 100%; overflow: hidden; font: 13px/1.35 system-ui, sans-serif; color: #222; background: #fff; }
#view { position: absolute; left: 0; top: 0; right: 360px; bottom: 0; }
#panel { position: absolute; top: 0; right: 0; width: 360px; bottom: 0; overflow-y: auto; box-sizing: border-box;
         padding: 10px 12px; background: #f6f6f4; border-left: 1px solid #ccc; overflow-x: hidden; }
#panel h1 { font-size: 15px; margin: 0 0 6px; word-break: break-all; }
#panel h2 { font-size: 13px; margin: 12px 0 4px; border-bottom: 1px solid #ccc; }
#panel table { border-collapse: collapse; width: 100%; }
#panel td, #panel th { padding: 1px 4px; text-align: left; vertical-align: top; }
#panel td.n { text-align: right; font-variant-numeric: tabular-nums; }
#status { font-weight: bold; font-size: 14px; padding: 4px 6px; border-radius: 3px; }
.status-ok { background: #cdeccd; } .status-ambiguous { background: #f6e3a8; }
.status-degenerate, .status-failed { background: #f3c0c0; } .status-other { background: #dde4ee; }
#message, .note { margin: 6px 0; white-space: pre-wrap; }
.note { color: #8a4b00; }
tr.candidate { cursor: pointer; } tr.candidate:hover { background: #e4ecf7; }
tr.shown { background: #cfe0f7 !important; } tr.winner td:first-child::after { content: " \2605"; }
label.toggle { display: block; cursor: pointer; }
.swatch { display: inline-block; width: 11px; height: 11px; margin-right: 4px; border: 1px solid #777; vertical-align: -1px; }
button { margin: 2px 4px 2px 0; }
#pick { position: absolute; left: 8px; bottom: 8px; max-width: 520px; background: rgba(255,255,255,0.92);
        border: 1px solid #bbb; padding: 6px 8px; display: none; font-size: 12px; }
#pick table td { padding: 0 4px; font-variant-numeric: tabular-nums; }
#page-error, #no-webgl { position: absolute; left: 8px; top: 28px; max-width: 520px; padding: 8px 10px; font-size: 13px;
                        background: #fbe4e4; border: 1px solid #c66; color: #600; white-space: pre-wrap; }
#no-webgl { background: #fff4d6; border-color: #c9a23a; color: #5a4200; }
#help { position: absolute; left: 8px; top: 6px; color: #555; font-size: 12px; background: rgba(255,255,255,0.7); }
)CSS";

const char* const kPageErrorHook = R"JS(
(function () {
  'use strict';
  window.quadrixErrors = [];
  function record(message) {
    window.quadrixErrors.push(message);
    document.body.setAttribute('data-error', window.quadrixErrors.join(' | '));
    document.title = 'quadrix view error: ' + message;
    // Shown, not only recorded: a page that failed says so in visible text.
    var banner = document.getElementById('page-error');
    if (!banner) {
      banner = document.createElement('div');
      banner.id = 'page-error';
      document.body.appendChild(banner);
    }
    banner.textContent = 'This page hit an error: ' + window.quadrixErrors.join(' | ');
  }
  window.addEventListener('error', function (event) {
    record((event.message || 'error') + (event.filename ? ' (' + event.filename + ':' + event.lineno + ')' : ''));
  });
  window.addEventListener('unhandledrejection', function (event) { record('unhandled rejection: ' + event.reason); });
  var consoleError = console.error.bind(console);
  console.error = function () {
    record(Array.prototype.map.call(arguments, String).join(' '));
    consoleError.apply(null, arguments);
  };
})();
)JS";

const char* const kPageScript = R"JS(
(function () {
  'use strict';
  if (typeof THREE === 'undefined' || typeof THREE.OrbitControls === 'undefined')
    throw new Error('three.js or its OrbitControls did not load');
  var stages = ['script ' + performance.now().toFixed(0)];  // where the time to the first frame goes, ms since opening
  var data = JSON.parse(document.getElementById('quadrix-data').textContent);
  stages.push('data ' + performance.now().toFixed(0));
  var viewElement = document.getElementById('view');
  var panel = document.getElementById('panel');
  var pick = document.getElementById('pick');

  // ---- data decoding: base64 of little-endian float32 / uint32 arrays ----
  var alphabet = 'ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/', sextet = new Uint8Array(128);
  for (var a = 0; a < 64; ++a) sextet[alphabet.charCodeAt(a)] = a;
  function bytesOf(text) {  // a table decoder: faster than atob + charCodeAt copies on megabytes
    var n = text.length, padding = n && text[n - 1] === '=' ? (text[n - 2] === '=' ? 2 : 1) : 0;
    var bytes = new Uint8Array(n / 4 * 3 - padding), size = bytes.length, j = 0;
    for (var i = 0; i < n; i += 4) {
      var v = (sextet[text.charCodeAt(i)] << 18) | (sextet[text.charCodeAt(i + 1)] << 12) |
              (sextet[text.charCodeAt(i + 2)] << 6) | sextet[text.charCodeAt(i + 3)];
      bytes[j++] = v >> 16;
      if (j < size) bytes[j++] = (v >> 8) & 255;
      if (j < size) bytes[j++] = v & 255;
    }
    return bytes.buffer;
  }
  function floats(base64) { return base64 ? new Float32Array(bytesOf(base64)) : new Float32Array(0); }
  function uints(base64) { return base64 ? new Uint32Array(bytesOf(base64)) : new Uint32Array(0); }
  // Points written as 16-bit grid coordinates (interactive_page.cpp quantized_points) back to metres.
  function pointPositionsOf(points) {
    var grid = new Uint16Array(bytesOf(points.data)), positions = new Float32Array(grid.length);
    var o = points.origin, s = points.step;
    for (var i = 0; i < grid.length; i += 3) {
      positions[i] = o[0] + s[0] * grid[i]; positions[i + 1] = o[1] + s[1] * grid[i + 1]; positions[i + 2] = o[2] + s[2] * grid[i + 2];
    }
    return positions;
  }
  // An element built from data: attributes set as attributes, children appended, strings as text
  // nodes. Data never becomes markup (no innerHTML anywhere), so a crafted report cannot run script.
  function el(tag, attributes, children) {
    var node = document.createElement(tag);
    Object.keys(attributes || {}).forEach(function (name) { node.setAttribute(name, String(attributes[name])); });
    (children || []).forEach(function (child) {
      if (child === null || child === undefined) return;
      node.appendChild(typeof child === 'object' ? child : document.createTextNode(String(child)));
    });
    return node;
  }
  function swatch(colour) {
    var node = el('span', {'class': 'swatch'});
    node.style.background = colour;
    return node;
  }
  function number(value, digits) {
    if (value === null || value === undefined) return '-';
    if (typeof value !== 'number') return String(value);
    if (Number.isInteger(value) && Math.abs(value) < 1e15) return String(value);
    return Math.abs(value) >= 1e5 || (value !== 0 && Math.abs(value) < 1e-3) ? value.toExponential(digits === undefined ? 3 : digits)
                                                                              : value.toFixed(digits === undefined ? 3 : digits);
  }
  function rgb(c) { return 'rgb(' + Number(c[0]) + ',' + Number(c[1]) + ',' + Number(c[2]) + ')'; }

  // ---- three.js scene ----
  // Without a WebGL context (a browser with WebGL off, a remote desktop, headless without a GPU)
  // the panel is still built and the view says so in visible text.
  var renderer = null, errorsBefore = window.quadrixErrors.length;
  try {
    renderer = new THREE.WebGLRenderer({antialias: data.kind === 'model', preserveDrawingBuffer: true});  // points need no MSAA (costly in software GL)
  } catch (error) {
    window.quadrixErrors.length = errorsBefore;  // three.js logged the failure; it is reported below instead
    if (errorsBefore === 0) {
      document.body.removeAttribute('data-error');
      document.title = 'quadrix view';
      var banner = document.getElementById('page-error');
      if (banner) banner.parentNode.removeChild(banner);
    }
    document.body.setAttribute('data-webgl', 'missing');
    viewElement.appendChild(el('div', {id: 'no-webgl'}, [
      'No 3D view: this browser could not create a WebGL context (' + ((error && error.message) || error) + ').\n' +
      'Turn on WebGL or hardware acceleration, or open the page in another browser. The report is in the panel.']));
  }
  stages.push('webgl ' + performance.now().toFixed(0));
  var canvas = renderer ? renderer.domElement : viewElement;
  if (renderer) {
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    renderer.setClearColor(0xffffff, 1);
    viewElement.appendChild(renderer.domElement);
  }
  var scene = new THREE.Scene();
  var camera = new THREE.PerspectiveCamera(45, 1, 0.05, 20000);
  camera.up.set(0, 0, 1);  // every quadrix frame is z up
  var controls = new THREE.OrbitControls(camera, canvas);
  controls.screenSpacePanning = true;
  scene.add(new THREE.AmbientLight(0xffffff, 0.5));
  var sun = new THREE.DirectionalLight(0xffffff, 0.55);
  sun.position.set(0.4, -0.6, 1.0);
  scene.add(sun);
  var fill = new THREE.DirectionalLight(0xffffff, 0.25);
  fill.position.set(-0.6, 0.5, 0.3);
  scene.add(fill);
  var frameRequested = false;
  function render() { frameRequested = false; if (renderer) renderer.render(scene, camera); }
  function requestRender() {
    if (!frameRequested) { frameRequested = true; requestAnimationFrame(render); }
  }
  controls.addEventListener('change', requestRender);
  function resize() {
    var width = Math.max(viewElement.clientWidth, 1), height = Math.max(viewElement.clientHeight, 1);
    if (renderer) renderer.setSize(width, height);
    camera.aspect = width / height;
    camera.updateProjectionMatrix();
    requestRender();
  }
  window.addEventListener('resize', resize);

  function pointsObject(positions, colour, size) {
    var geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    return new THREE.Points(geometry, new THREE.PointsMaterial({color: colour, size: size, sizeAttenuation: false}));
  }
  // Points coloured by height (blue-grey low, warm grey high), so the meshes in front stay readable.
  function heightPointsObject(positions, size) {
    var geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    var count = positions.length / 3, low = Infinity, high = -Infinity, i;
    for (i = 0; i < count; ++i) { low = Math.min(low, positions[3 * i + 2]); high = Math.max(high, positions[3 * i + 2]); }
    var colours = new Float32Array(positions.length), span = Math.max(high - low, 1e-6);
    for (i = 0; i < count; ++i) {
      var f = (positions[3 * i + 2] - low) / span;
      colours[3 * i] = 0.45 + 0.25 * f; colours[3 * i + 1] = 0.5 + 0.15 * f; colours[3 * i + 2] = 0.62 - 0.1 * f;
    }
    geometry.setAttribute('color', new THREE.BufferAttribute(colours, 3));
    return new THREE.Points(geometry, new THREE.PointsMaterial({size: size, sizeAttenuation: false, vertexColors: THREE.VertexColors}));
  }

  // A robust frame: the box between the 2nd and 98th percentiles of a sample of the points.
  function frameOn(arrays) {
    var xs = [], ys = [], zs = [];
    arrays.forEach(function (positions) {
      var count = positions.length / 3, stride = Math.max(1, Math.floor(count / 20000));
      for (var i = 0; i < count; i += stride) { xs.push(positions[3 * i]); ys.push(positions[3 * i + 1]); zs.push(positions[3 * i + 2]); }
    });
    if (xs.length === 0) { xs = [-1, 1]; ys = [-1, 1]; zs = [-1, 1]; }
    function range(values) {
      values.sort(function (a, b) { return a - b; });
      return [values[Math.floor(0.02 * (values.length - 1))], values[Math.ceil(0.98 * (values.length - 1))]];
    }
    var x = range(xs), y = range(ys), z = range(zs);
    var centre = new THREE.Vector3((x[0] + x[1]) / 2, (y[0] + y[1]) / 2, (z[0] + z[1]) / 2);
    var radius = Math.max(0.5 * Math.hypot(x[1] - x[0], y[1] - y[0], z[1] - z[0]), 1.0);
    controls.target.copy(centre);
    var distance = radius / Math.sin(camera.fov * Math.PI / 360) * 1.05;
    camera.position.set(centre.x - 0.45 * distance, centre.y - 0.7 * distance, centre.z + 0.55 * distance);
    camera.near = Math.max(distance / 2000, 0.01);
    camera.far = distance * 20;
    camera.updateProjectionMatrix();
    controls.update();
  }

  function statusBlock(status, message, note) {
    var known = ['ok', 'ambiguous', 'degenerate', 'failed'].indexOf(status) >= 0;
    return [el('div', {id: 'status', 'class': 'status-' + (known ? status : 'other')}, ['status: ' + status]),
            message ? el('div', {id: 'message'}, [message]) : null, note ? el('div', {'class': 'note'}, [note]) : null];
  }
  function table(rows) {
    return el('table', {}, rows.map(function (row) { return el('tr', {}, [el('td', {}, [row[0]]), el('td', {'class': 'n'}, [row[1]])]); }));
  }
  function appendAll(parent, children) {
    children.forEach(function (child) {
      if (child === null || child === undefined) return;
      if (Array.isArray(child)) appendAll(parent, child);
      else parent.appendChild(typeof child === 'object' ? child : document.createTextNode(String(child)));
    });
  }

  // ---- registration page ----
  function registrationPage() {
    var report = data.report;
    var sourcePositions = pointPositionsOf(data.source), targetPositions = pointPositionsOf(data.target);
    stages.push('points ' + performance.now().toFixed(0));
    var target = pointsObject(targetPositions, 0x9a9a9a, 1.5);
    var source = pointsObject(sourcePositions, 0xff7800, 1.5);
    source.matrixAutoUpdate = false;
    scene.add(target);
    scene.add(source);
    var hasModels = !!(data.source_model && data.target_model);
    var sourceCentres = hasModels ? floats(data.source_model.centres) : new Float32Array(0);
    var targetCentres = hasModels ? floats(data.target_model.centres) : new Float32Array(0);
    var lineGeometry = new THREE.BufferGeometry();
    var lines = new THREE.LineSegments(lineGeometry, new THREE.LineBasicMaterial({color: 0x0a8a2a}));
    var endGeometry = new THREE.BufferGeometry();
    var ends = new THREE.Points(endGeometry, new THREE.PointsMaterial({color: 0x1040c0, size: 7, sizeAttenuation: false}));
    scene.add(lines);
    scene.add(ends);

    var candidates = report.candidates || [];
    var winner = -1;
    candidates.forEach(function (c, i) { if (c.selected) winner = i; });
    var state = {aligned: true, shown: -1, lines: true};  // shown: -1 = the reported answer, else a candidate index

    function matrixOf(rows) {
      var m = new THREE.Matrix4();
      m.set(rows[0][0], rows[0][1], rows[0][2], rows[0][3], rows[1][0], rows[1][1], rows[1][2], rows[1][3],
            rows[2][0], rows[2][1], rows[2][2], rows[2][3], rows[3][0], rows[3][1], rows[3][2], rows[3][3]);
      return m;
    }
    function currentClique() {
      var index = state.shown >= 0 ? state.shown : winner;
      return index >= 0 && candidates[index].clique ? candidates[index].clique : [];
    }
    function update() {
      var rows = state.shown >= 0 ? candidates[state.shown].transform : report.transform;
      var m = state.aligned ? matrixOf(rows) : new THREE.Matrix4();
      source.matrix.copy(m);
      source.matrixWorldNeedsUpdate = true;
      // Correspondence lines: source record centre (moved like the source) -> target record centre.
      var clique = hasModels ? currentClique() : [];
      var segment = new Float32Array(6 * clique.length), v = new THREE.Vector3();
      clique.forEach(function (pair, k) {
        v.set(sourceCentres[3 * pair[0]], sourceCentres[3 * pair[0] + 1], sourceCentres[3 * pair[0] + 2]).applyMatrix4(m);
        segment[6 * k] = v.x; segment[6 * k + 1] = v.y; segment[6 * k + 2] = v.z;
        segment[6 * k + 3] = targetCentres[3 * pair[1]]; segment[6 * k + 4] = targetCentres[3 * pair[1] + 1];
        segment[6 * k + 5] = targetCentres[3 * pair[1] + 2];
      });
      lineGeometry.setAttribute('position', new THREE.BufferAttribute(segment, 3));
      lineGeometry.computeBoundingSphere();
      endGeometry.setAttribute('position', new THREE.BufferAttribute(segment.slice(), 3));
      endGeometry.computeBoundingSphere();
      lines.visible = ends.visible = state.lines;
      Array.prototype.forEach.call(panel.querySelectorAll('tr.candidate'), function (row) {
        row.classList.toggle('shown', Number(row.getAttribute('data-index')) === state.shown);
      });
      document.getElementById('shown').textContent = state.shown >= 0
          ? 'candidate ' + state.shown + ' (level ' + candidates[state.shown].level + ', clique of ' + clique.length + ')'
          : 'the reported answer (clique of ' + clique.length + ')';
      requestRender();
    }

    var counts = report.counts || {}, timings = report.timings_ms || {};
    var candidateRows = [el('tr', {}, ['#', 'δm', '|I*|', 'refine', 'score'].map(function (h) { return el('th', {}, [h]); }))];
    candidates.forEach(function (c, i) {
      candidateRows.push(el('tr', {'class': 'candidate' + (i === winner ? ' winner' : ''), 'data-index': i, title: c.note || ''}, [
        el('td', {}, [i]), el('td', {'class': 'n'}, [number(c.threshold_m, 1)]), el('td', {'class': 'n'}, [number(c.clique_size, 0)]),
        el('td', {}, [String(c.refinement_status) + (c.valid ? '' : ' (invalid)')]), el('td', {'class': 'n'}, [number(c.score, 4)])]));
    });
    var lineToggle = el('input', {type: 'checkbox', id: 'lines', checked: ''});
    appendAll(panel, [
      el('h1', {}, [data.title]), statusBlock(report.status, report.message, data.note),
      el('div', {}, [el('button', {id: 'show-aligned'}, ['source aligned']), el('button', {id: 'show-scanned'}, ['source as scanned']),
                     el('button', {id: 'show-answer'}, ['reported answer']),
                     el('label', {'class': 'toggle', style: 'display:inline'}, [lineToggle, ' lines'])]),
      el('div', {}, ['showing: ', el('span', {id: 'shown'})]),
      el('div', {}, [swatch('#9a9a9a'), 'target (' + number(data.target_total || 0, 0) + ' points) ', swatch('#ff7800'),
                     'source (' + number(data.source_total || 0, 0) + ') ', swatch('#0a8a2a'), 'clique']),
      report.ground_truth ? [el('h2', {}, ['Ground truth']),
                             table([['RTE (m)', number(report.ground_truth.rte_m)], ['RRE (deg)', number(report.ground_truth.rre_deg)],
                                    ['success', report.ground_truth.success ? 'yes' : 'no']])] : null,
      el('h2', {}, ['Candidates (click one to apply it)']), el('table', {}, candidateRows),
      report.best_to_second_ratio !== null && report.best_to_second_ratio !== undefined
          ? el('div', {}, ['best / second score: ' + number(report.best_to_second_ratio)]) : null,
      el('h2', {}, ['Timings (ms)']), table(Object.keys(timings).map(function (k) { return [k, number(timings[k], 1)]; })),
      el('h2', {}, ['Counts']), table(Object.keys(counts).map(function (k) {
        return [k, Array.isArray(counts[k]) ? counts[k].map(String).join(' / ') : number(counts[k], 0)];
      })),
      report.overlap ? [el('h2', {}, ['Overlap']),
                        table([['answer', number(report.overlap.transformed)], ['unmoved', number(report.overlap.identity)],
                               ['distance (m)', number(report.overlap.distance_m, 2)]])] : null,
      report.input ? [el('h2', {}, ['Input']),
                      table([['source', report.input.source], ['target', report.input.target],
                             ['presets', report.input.source_preset + ' / ' + report.input.target_preset]])] : null]);
    document.getElementById('show-aligned').onclick = function () { state.aligned = true; update(); };
    document.getElementById('show-scanned').onclick = function () { state.aligned = false; update(); };
    document.getElementById('show-answer').onclick = function () { state.shown = -1; state.aligned = true; update(); };
    document.getElementById('lines').onchange = function (event) { state.lines = event.target.checked; update(); };
    Array.prototype.forEach.call(panel.querySelectorAll('tr.candidate'), function (row) {
      row.onclick = function () { state.shown = Number(row.getAttribute('data-index')); state.aligned = true; update(); };
    });
    // "#candidate=K" in the address applies candidate K at opening (links, scripted checks).
    var asked = /candidate=(\d+)/.exec(location.hash);
    if (asked && Number(asked[1]) < candidates.length) state.shown = Number(asked[1]);
    if (/scanned/.test(location.hash)) state.aligned = false;  // "#scanned": the source in its own frame
    update();
    frameOn([targetPositions]);
  }

  // ---- model page ----
  var recordNames = ['l', 'A', 'B', 'C', 'D', 'E', 'F', 'G', 'H', 'I', 'J', 's_f a', 's_f b', 's_f c', 'η_f w', 'η_f x', 'η_f y', 'η_f z',
                     't_f x', 't_f y', 't_f z'];
  function modelPage() {
    var pointPositions = pointPositionsOf(data.points);
    var cloud = pointPositions.length ? heightPointsObject(pointPositions, 1.2) : null;
    if (cloud) scene.add(cloud);
    stages.push('points ' + performance.now().toFixed(0));
    var meshes = [], typeOn = {}, classOn = {}, typeCount = {}, classCount = {}, typeColour = {};
    var meshPositions = [];
    data.quadrics.forEach(function (q) {
      typeOn[q.type] = true; classOn[q.class] = true;
      typeCount[q.type] = (typeCount[q.type] || 0) + 1; classCount[q.class] = (classCount[q.class] || 0) + 1;
      typeColour[q.type] = q.colour;
      var vertices = floats(q.vertices), triangles = uints(q.triangles);
      if (triangles.length === 0) return;
      var geometry = new THREE.BufferGeometry();
      geometry.setAttribute('position', new THREE.BufferAttribute(vertices, 3));
      geometry.setIndex(new THREE.BufferAttribute(triangles, 1));
      geometry.computeVertexNormals();
      var colour = new THREE.Color(q.colour[0] / 255, q.colour[1] / 255, q.colour[2] / 255);
      var mesh = new THREE.Mesh(geometry, new THREE.MeshLambertMaterial({color: colour, side: THREE.DoubleSide}));
      mesh.userData.quadric = q;
      meshes.push(mesh);
      if (q.class !== 'ground' && q.class !== 'road') meshPositions.push(vertices);  // frame the structures, not the ground
      scene.add(mesh);
    });
    stages.push('meshes ' + performance.now().toFixed(0));
    var picked = null;
    function applyVisibility() {
      meshes.forEach(function (mesh) {
        var q = mesh.userData.quadric;
        mesh.visible = typeOn[q.type] && classOn[q.class];
      });
      if (cloud) cloud.visible = document.getElementById('points').checked;
      requestRender();
    }
    function showPick(mesh) {
      if (picked) picked.material.emissive.setHex(0x000000);
      picked = mesh;
      if (!mesh) { pick.style.display = 'none'; requestRender(); return; }
      mesh.material.emissive.setHex(0x553300);
      var q = mesh.userData.quadric, rows = [];
      for (var row = 0; row < 7; ++row) {
        var cells = [];
        for (var col = 0; col < 3; ++col) {
          var k = row * 3 + col;
          cells.push(el('td', {}, [recordNames[k]]), el('td', {'class': 'n'}, [number(q.record[k], 4)]));
        }
        rows.push(el('tr', {}, cells));
      }
      pick.textContent = '';
      appendAll(pick, [el('b', {}, ['quadric ' + q.index]), ': ' + q.type + ', class ' + q.class + ', ' + q.points + ' points', el('br'),
                  '21-number record (paper Struct. 1):', el('table', {}, rows)]);
      pick.style.display = 'block';
      requestRender();
    }
    var typeToggles = Object.keys(typeCount).sort().map(function (t) {
      return el('label', {'class': 'toggle'}, [el('input', {type: 'checkbox', 'data-type': t, checked: ''}), swatch(rgb(typeColour[t])),
                                               t + ' (' + typeCount[t] + ')']);
    });
    var classToggles = Object.keys(classCount).sort().map(function (c) {
      return el('label', {'class': 'toggle'}, [el('input', {type: 'checkbox', 'data-class': c, checked: ''}), c + ' (' + classCount[c] + ')']);
    });
    var pointsToggle = el('input', cloud ? {type: 'checkbox', id: 'points', checked: ''} : {type: 'checkbox', id: 'points', disabled: ''});
    appendAll(panel, [
      el('h1', {}, [data.title]), statusBlock(data.status, data.message, ''),
      table((data.facts || []).map(function (f) { return [f[0], f[1]]; })),
      el('div', {}, [data.quadrics.length + ' quadrics; click one for its record']),
      el('h2', {}, ['Types']), typeToggles, el('h2', {}, ['Classes']), classToggles,
      el('h2', {}, ['Points']),
      el('label', {'class': 'toggle'}, [pointsToggle, ' points (' + (pointPositions.length / 3) + ' shown of ' + number(data.points_total || 0, 0) + ')'])]);
    Array.prototype.forEach.call(panel.querySelectorAll('input[data-type]'), function (box) {
      box.onchange = function () { typeOn[box.getAttribute('data-type')] = box.checked; applyVisibility(); };
    });
    Array.prototype.forEach.call(panel.querySelectorAll('input[data-class]'), function (box) {
      box.onchange = function () { classOn[box.getAttribute('data-class')] = box.checked; applyVisibility(); };
    });
    document.getElementById('points').onchange = applyVisibility;
    // A click (not a drag) picks the nearest visible quadric under the pointer.
    var raycaster = new THREE.Raycaster(), down = null;
    canvas.addEventListener('pointerdown', function (event) { down = [event.clientX, event.clientY]; });
    canvas.addEventListener('pointerup', function (event) {
      if (!down || Math.hypot(event.clientX - down[0], event.clientY - down[1]) > 4) return;
      var box = canvas.getBoundingClientRect();
      var ndc = new THREE.Vector2(((event.clientX - box.left) / box.width) * 2 - 1, -((event.clientY - box.top) / box.height) * 2 + 1);
      raycaster.setFromCamera(ndc, camera);
      var hits = raycaster.intersectObjects(meshes.filter(function (m) { return m.visible; }));
      showPick(hits.length ? hits[0].object : null);
    });
    window.quadrixPick = function (index) {  // for scripted checks: pick quadric `index` as a click would
      var mesh = meshes.filter(function (m) { return m.userData.quadric.index === index; })[0] || null;
      showPick(mesh);
      return !!mesh;
    };
    frameOn(meshPositions.length ? meshPositions : [pointPositions]);
    // "#pick=K" in the address picks quadric K at opening, as a click on it would.
    var asked = /pick=(\d+)/.exec(location.hash);
    if (asked) window.quadrixPick(Number(asked[1]));
  }

  if (data.kind === 'registration') registrationPage();
  else if (data.kind === 'model') modelPage();
  else throw new Error('unknown page kind ' + data.kind);
  var help = document.createElement('div');
  help.id = 'help';
  help.textContent = 'drag: rotate · right-drag: pan · wheel: zoom';
  viewElement.appendChild(help);
  stages.push('scene ' + performance.now().toFixed(0));
  resize();
  render();  // the first frame, drawn before the page reports itself ready
  if (renderer) renderer.getContext().finish();  // drawn, not only queued
  var ready = performance.now();
  stages.push('frame ' + ready.toFixed(0));
  document.body.setAttribute('data-stages', stages.join(', '));
  document.body.setAttribute('data-ready-ms', ready.toFixed(0));
  if (!document.body.hasAttribute('data-error'))
    document.title = 'quadrix view ready ' + ready.toFixed(0) + ' ms' + (renderer ? '' : ' (no WebGL: panel only)');
})();
)JS";

}  // namespace quadrix
