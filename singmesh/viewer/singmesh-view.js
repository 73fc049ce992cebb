/* singmesh interactive view: one mesh in a WebGL canvas, drawn with three.js (global THREE).
 *
 * singmeshView(container, data) draws the mesh described by `data` (the JSON of
 * singmesh.view.view_data) into `container` and returns a small handle, or null when
 * three.js or WebGL is missing (the container then says why in words).
 *
 * Orange is the side grad F points to, blue the other side (faces are counter-clockwise
 * around grad F, so the front faces are the grad F side); singular points are spheres
 * coloured by type, singular curves red tubes, isolated real lines dashed violet ones.
 *
 * The controls are our own (drag: turn about the vertical axis and tilt; wheel or pinch:
 * zoom; shift-drag, right-drag or two fingers: pan; double-click: back to the start):
 * three's OrbitControls ships only as an ES module, which a page opened from disk
 * (file://) cannot import, and a turntable about z keeps "up" up as in the PNG pictures.
 *
 * The picture is redrawn only when something changes (no animation loop), so an idle page
 * costs nothing.  The container gets data-state="drawn" after the first frame (tests wait
 * for it), or "failed" with the reason as its text.
 */
(function (global) {
  'use strict';

  function bytes(b64) {
    var bin = global.atob(b64);
    var out = new Uint8Array(bin.length);
    for (var i = 0; i < bin.length; i++) out[i] = bin.charCodeAt(i);
    return out.buffer;
  }

  function fail(container, text) {
    container.setAttribute('data-state', 'failed');
    var p = document.createElement('p');
    p.className = 'singmesh-view-message';
    p.textContent = text;
    container.appendChild(p);
    return null;
  }

  // Pieces of the curve edges (point pairs) to draw: all of them, or for a dashed line
  // (`period` > 0) the first 60% of every `period` of arc length along them.
  function pieces(p, period) {
    if (!(period > 0)) return p;
    var out = [], s = 0;
    for (var i = 0; i < p.length; i += 6) {
      var d = [p[i + 3] - p[i], p[i + 4] - p[i + 1], p[i + 5] - p[i + 2]];
      var length = Math.hypot(d[0], d[1], d[2]);
      for (var k = Math.floor(s / period); k * period < s + length; k++) {
        var t0 = Math.max(0, k * period - s), t1 = Math.min(length, k * period + 0.6 * period - s);
        if (t1 <= t0 || length === 0) continue;
        out.push(p[i] + d[0] * t0 / length, p[i + 1] + d[1] * t0 / length, p[i + 2] + d[2] * t0 / length,
                 p[i] + d[0] * t1 / length, p[i + 1] + d[1] * t1 / length, p[i + 2] + d[2] * t1 / length);
      }
      s += length;
    }
    return out;
  }

  // Curve edges as thin cylinders, one instanced mesh: WebGL draws lines one pixel wide
  // whatever is asked, too thin to see on a surface.
  function tubes(THREE, b64, colour, radius, period) {
    var p = pieces(new Float32Array(bytes(b64)), period);
    var n = p.length / 6;
    var cylinder = new THREE.CylinderGeometry(radius, radius, 1, 8, 1, false);
    cylinder.translate(0, 0.5, 0);   // from its base at the origin up to y = 1
    var mesh = new THREE.InstancedMesh(cylinder, new THREE.MeshPhongMaterial({ color: colour, shininess: 30 }), n);
    var a = new THREE.Vector3(), d = new THREE.Vector3(), y = new THREE.Vector3(0, 1, 0);
    var q = new THREE.Quaternion(), scale = new THREE.Vector3(), m = new THREE.Matrix4();
    for (var i = 0; i < n; i++) {
      a.set(p[6 * i], p[6 * i + 1], p[6 * i + 2]);
      d.set(p[6 * i + 3], p[6 * i + 4], p[6 * i + 5]).sub(a);
      var length = d.length();
      q.setFromUnitVectors(y, length > 0 ? d.divideScalar(length) : y);
      scale.set(1, length, 1);
      mesh.setMatrixAt(i, m.compose(a, q, scale));
    }
    mesh.instanceMatrix.needsUpdate = true;
    return mesh;
  }

  function singmeshView(container, data) {
    var THREE = global.THREE;
    if (!THREE) return fail(container, 'The 3-D view needs three.js, which did not load.');
    var renderer;
    try {
      renderer = new THREE.WebGLRenderer({ antialias: true });
    } catch (e) {
      return fail(container, 'The 3-D view needs WebGL, which this browser does not provide (' + e.message + ').');
    }
    var c = data.colours;
    var box = data.box;
    var centre = new THREE.Vector3((box[0][0] + box[0][1]) / 2, (box[1][0] + box[1][1]) / 2,
                                   (box[2][0] + box[2][1]) / 2);
    var size = new THREE.Vector3(box[0][1] - box[0][0], box[1][1] - box[1][0], box[2][1] - box[2][0]);
    var radius = 0.5 * size.length();

    var scene = new THREE.Scene();
    scene.background = new THREE.Color(c.background);

    // The surface: the same geometry twice, front faces orange and back faces blue.  The
    // polygon offset pushes it back a little so that curves lying on it stay visible.
    if (data.faces) {
      var geometry = new THREE.BufferGeometry();
      geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(bytes(data.vertices)), 3));
      geometry.setAttribute('normal', new THREE.BufferAttribute(new Int8Array(bytes(data.normals)), 3, true));
      var index = data.index === 'u16' ? new Uint16Array(bytes(data.faces)) : new Uint32Array(bytes(data.faces));
      geometry.setIndex(new THREE.BufferAttribute(index, 1));
      [[c.front, THREE.FrontSide], [c.back, THREE.BackSide]].forEach(function (s) {
        var m = new THREE.MeshPhongMaterial({ color: s[0], side: s[1], shininess: 40, specular: 0x2a2a2a,
                                              polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 });
        scene.add(new THREE.Mesh(geometry, m));
      });
    }
    if (data.curves) scene.add(tubes(THREE, data.curves, c.curve, data.curve_radius * radius, 0));
    if (data.isolated) scene.add(tubes(THREE, data.isolated, c.isolated, data.curve_radius * radius, 0.04 * radius));
    var ball = new THREE.SphereGeometry(data.point_radius * radius, 20, 14);
    data.points.forEach(function (p) {
      var s = new THREE.Mesh(ball, new THREE.MeshPhongMaterial({ color: p.colour, shininess: 60 }));
      s.position.set(p.at[0], p.at[1], p.at[2]);
      s.renderOrder = 3;
      scene.add(s);
    });
    var frame = new THREE.LineSegments(new THREE.EdgesGeometry(new THREE.BoxGeometry(size.x, size.y, size.z)),
                                       new THREE.LineBasicMaterial({ color: c.box, transparent: true, opacity: 0.6 }));
    frame.position.copy(centre);
    scene.add(frame);

    // Lights ride with the camera (as in the PNG pictures): every view is lit the same way.
    var camera = new THREE.PerspectiveCamera(30, 1, radius / 100, radius * 100);
    camera.up.set(0, 0, 1);
    scene.add(camera);
    scene.add(new THREE.AmbientLight(0xffffff, 0.9));
    var key = new THREE.DirectionalLight(0xffffff, 1.9);
    key.position.set(-0.45, 0.65, 0.62);
    camera.add(key);
    var fill = new THREE.DirectionalLight(0xffffff, 0.7);
    fill.position.set(0.55, -0.25, 0.8);
    camera.add(fill);
    // Directional lights shine from their position towards their target; targets in the
    // camera's frame follow it.
    key.target.position.set(0, 0, -1); camera.add(key.target);
    fill.target.position.set(0, 0, -1); camera.add(fill.target);

    var start = { az: data.azimuth * Math.PI / 180, el: data.elevation * Math.PI / 180, dist: 1 };
    var view = { az: start.az, el: start.el, dist: 1, target: centre.clone(), moved: false };
    // The distance at which the box's bounding sphere fits the narrower of the two angles of view.
    function startDistance() {
      var half = Math.atan(Math.tan(camera.fov * Math.PI / 360) * Math.min(1, camera.aspect));
      return radius / Math.sin(half);
    }
    var pending = false;

    function place() {
      var ce = Math.cos(view.el);
      camera.position.set(ce * Math.cos(view.az), ce * Math.sin(view.az), Math.sin(view.el))
        .multiplyScalar(view.dist).add(view.target);
      camera.lookAt(view.target);
    }
    function draw() {
      pending = false;
      place();
      renderer.render(scene, camera);
      container.setAttribute('data-state', 'drawn');
    }
    function redraw() {
      if (!pending) { pending = true; global.requestAnimationFrame(draw); }
    }
    function fit() {
      var w = Math.max(1, container.clientWidth), h = Math.max(1, container.clientHeight);
      renderer.setPixelRatio(global.devicePixelRatio || 1);
      renderer.setSize(w, h, false);
      camera.aspect = w / h;
      camera.updateProjectionMatrix();
      start.dist = startDistance();
      if (!view.moved) view.dist = start.dist;
      redraw();
    }

    var canvas = renderer.domElement;
    canvas.className = 'singmesh-view-canvas';
    canvas.style.touchAction = 'none';
    container.insertBefore(canvas, container.firstChild);

    // Pointer controls: one pointer turns (or pans with shift / the right button), two pinch.
    var pointers = {};
    function count() { return Object.keys(pointers).length; }
    function spread() {
      var p = Object.keys(pointers).map(function (k) { return pointers[k]; });
      return Math.hypot(p[0].x - p[1].x, p[0].y - p[1].y);
    }
    function pan(dx, dy) {
      var s = 2 * view.dist * Math.tan(camera.fov * Math.PI / 360) / Math.max(1, container.clientHeight);
      var right = new THREE.Vector3().setFromMatrixColumn(camera.matrix, 0);
      var up = new THREE.Vector3().setFromMatrixColumn(camera.matrix, 1);
      view.target.addScaledVector(right, -dx * s).addScaledVector(up, dy * s);
    }
    canvas.addEventListener('contextmenu', function (e) { e.preventDefault(); });
    canvas.addEventListener('pointerdown', function (e) {
      canvas.setPointerCapture(e.pointerId);
      pointers[e.pointerId] = { x: e.clientX, y: e.clientY, pan: e.shiftKey || e.button === 2 || e.button === 1 };
      if (count() === 2) view.pinch = spread();
    });
    canvas.addEventListener('pointermove', function (e) {
      var p = pointers[e.pointerId];
      if (!p) return;
      var dx = e.clientX - p.x, dy = e.clientY - p.y;
      p.x = e.clientX; p.y = e.clientY;
      view.moved = true;
      if (count() === 2) {
        var d = spread();
        if (view.pinch > 0 && d > 0) view.dist *= view.pinch / d;
        view.pinch = d;
        pan(dx / 2, dy / 2);
      } else if (p.pan) {
        pan(dx, dy);
      } else {
        view.az -= dx * 0.01;
        view.el = Math.max(-1.55, Math.min(1.55, view.el + dy * 0.01));
      }
      redraw();
    });
    function up(e) { delete pointers[e.pointerId]; view.pinch = 0; }
    canvas.addEventListener('pointerup', up);
    canvas.addEventListener('pointercancel', up);
    canvas.addEventListener('wheel', function (e) {
      e.preventDefault();
      view.moved = true;
      view.dist *= Math.exp(Math.max(-1, Math.min(1, e.deltaY * 0.0015)));
      redraw();
    }, { passive: false });
    canvas.addEventListener('dblclick', function () {
      view.az = start.az; view.el = start.el; view.dist = start.dist; view.target.copy(centre);
      view.moved = false;
      redraw();
    });

    if (global.ResizeObserver) new global.ResizeObserver(fit).observe(container);
    else global.addEventListener('resize', fit);
    fit();
    return { renderer: renderer, scene: scene, camera: camera, view: view, redraw: redraw };
  }

  // Starts every view on the page whose data is in a <script type="application/json"> block.
  function startAll() {
    var nodes = document.querySelectorAll('.singmesh-view[data-view]');
    Array.prototype.forEach.call(nodes, function (el) {
      if (el.getAttribute('data-state')) return;
      var src = document.getElementById(el.getAttribute('data-view'));
      el.setAttribute('data-state', 'starting');
      singmeshView(el, JSON.parse(src.textContent));
    });
  }

  global.singmeshView = singmeshView;
  global.singmeshViewStartAll = startAll;
})(window);
