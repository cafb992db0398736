/* mazearena replay viewer.
 * Reads the match data from <script id="replay-data"> and draws the maze, the robot,
 * run 0's trail and visit heat map, run 1's path, the optimal route, the sensor rays
 * and the bot's own debug drawings as layers of one SVG, with a side panel for the
 * current step and playback controls. Plain ES2017, no libraries, no network.
 * Everything in the data comes from untrusted bots: text only ever goes through
 * textContent, and malformed entries are skipped without throwing. */
(function () {
  'use strict';

  var SVGNS = 'http://www.w3.org/2000/svg';
  var HEADINGS = ['up', 'right', 'down', 'left'];
  var DIRS = { up: [0, 1], right: [1, 0], down: [0, -1], left: [-1, 0] };
  var BASE_RATE = 4; // steps per second at 1x
  var DBG_FIELDS = ['text', 'walls', 'cells', 'grid', 'colors', 'path'];
  var COLOR_RE = /^#(?:[0-9a-fA-F]{3}|[0-9a-fA-F]{6})$/;
  var EVENT_LABELS = { move: 'move', reset_accepted: 'reset accepted', reset_rejected: 'reset rejected', goal_reached: 'goal reached' };

  // ---------- small helpers ----------
  function $(id) { return document.getElementById(id); }
  function isInt(v) { return typeof v === 'number' && Number.isInteger(v); }
  function isNum(v) { return typeof v === 'number' && isFinite(v); }
  function isObj(v) { return v !== null && typeof v === 'object' && !Array.isArray(v); }
  function clamp(v, lo, hi) { return v < lo ? lo : v > hi ? hi : v; }
  function r3(v) { return Math.round(v * 1000) / 1000; }
  function text(v, max) {
    if (typeof v === 'number' || typeof v === 'boolean') v = String(v);
    if (typeof v !== 'string') return '';
    max = max || 2000;
    return v.length > max ? v.slice(0, max) + '…' : v;
  }
  function html(tag, cls, content) {
    var e = document.createElement(tag);
    if (cls) e.className = cls;
    if (content != null) e.textContent = content;
    return e;
  }
  function svg(tag, attrs, parent) {
    var e = document.createElementNS(SVGNS, tag);
    for (var k in attrs) if (Object.prototype.hasOwnProperty.call(attrs, k)) e.setAttribute(k, attrs[k]);
    if (parent) parent.appendChild(e);
    return e;
  }
  function ms(us) { return isNum(us) ? (us / 1000).toFixed(1) + ' ms' : '—'; }

  // ---------- data ----------
  function readData() {
    var node = $('replay-data');
    if (!node) return {};
    try { var d = JSON.parse(node.textContent); return isObj(d) ? d : {}; } catch (e) { return {}; }
  }

  var parseLayout = mazearenaLayout.parse;

  function init() {
    var root = $('viewer');
    if (!root || root.getAttribute('data-ready')) return;
    root.setAttribute('data-ready', '1');
    var data = readData();
    var record = isObj(data.record) ? data.record : {};
    var trace = Array.isArray(record.trace) ? record.trace.map(function (s) { return isObj(s) ? s : {}; }) : [];
    var T = trace.length;
    // The bot's stderr is its owner's: a page shows it once the owner's token is given.
    var stderrHidden = data.stderr_hidden === true;
    var HIDDEN_STDERR = "the bot's stderr is shown to its owner: paste the owner token below the viewer";
    var layoutStr = data.maze && typeof data.maze.layout === 'string' ? data.maze.layout : null;
    var maze = parseLayout(layoutStr);
    var n = maze ? maze.n : [data.maze && data.maze.dim, record.maze_dim, 16].filter(function (v) { return isInt(v) && v >= 2 && v <= 64; })[0];

    // Precomputed per-step state: poses[k] is the pose after trace[k-1] (k = 0: start).
    var poses = [{ x: 0, y: 0, h: 'up' }];
    trace.forEach(function (s) {
      var p = poses[poses.length - 1], q = { x: p.x, y: p.y, h: p.h };
      if (isObj(s.position) && isInt(s.position.x) && isInt(s.position.y)) { q.x = s.position.x; q.y = s.position.y; }
      if (HEADINGS.indexOf(s.heading) >= 0) q.h = s.heading;
      poses.push(q);
    });
    function stepNo(i) { return isInt(trace[i].step) ? trace[i].step : i + 1; }
    function runOf(i) { return trace[i].run === 1 ? 1 : 0; }
    function inGrid(x, y) { return isInt(x) && isInt(y) && x >= 0 && y >= 0 && x < n && y < n; }
    function X(x) { return x + 0.5; }
    function Y(y) { return n - y - 0.5; }
    function pt(p) { return r3(X(p.x)) + ' ' + r3(Y(p.y)); }

    // Run 0 trail points, run 1 path points and the heat map's per-step visits.
    var trailPts = ['M' + pt(poses[0])], trailCount = [1];
    var run1Pts = [], run1Count = [0];
    var heatDelta = [], heatFinal = new Uint16Array(n * n);
    if (inGrid(0, 0)) heatFinal[0] = 1;
    var maxHeat = 1;
    trace.forEach(function (s, i) {
      var P = poses[i], Q = poses[i + 1], delta = [];
      var moved = P.x !== Q.x || P.y !== Q.y;
      if (s.event !== 'reset_accepted' && moved) {
        if (runOf(i) === 0) {
          trailPts.push('L' + pt(Q));
          var dx = Math.sign(Q.x - P.x), dy = Math.sign(Q.y - P.y);
          var cells = [];
          if (dx === 0 || dy === 0) {
            for (var c = { x: P.x + dx, y: P.y + dy }; ; c = { x: c.x + dx, y: c.y + dy }) {
              cells.push(c);
              if (c.x === Q.x && c.y === Q.y) break;
            }
          } else cells.push(Q);
          cells.forEach(function (c) {
            if (!inGrid(c.x, c.y)) return;
            var idx = c.x * n + c.y;
            delta.push(idx);
            heatFinal[idx]++;
            if (heatFinal[idx] > maxHeat) maxHeat = heatFinal[idx];
          });
        } else {
          if (run1Pts.length === 0) run1Pts.push('M' + pt(P));
          run1Pts.push('L' + pt(Q));
        }
      } else if (s.event !== 'reset_accepted' && runOf(i) === 1 && run1Pts.length === 0) {
        run1Pts.push('M' + pt(P));
      }
      heatDelta.push(delta);
      trailCount.push(trailPts.length);
      run1Count.push(run1Pts.length);
    });

    // Debug is sticky per field: dbgSrc[f][k] = trace index of the latest step <= k sending f, or -1.
    var dbgSrc = {};
    DBG_FIELDS.forEach(function (f) {
      var arr = new Int32Array(T + 1);
      arr[0] = -1;
      for (var i = 0; i < T; i++) {
        var d = trace[i].debug, has = false;
        if (isObj(d)) has = f === 'text' ? (typeof d.text === 'string' || isNum(d.text)) : Array.isArray(d[f]);
        arr[i + 1] = has ? i : arr[i];
      }
      dbgSrc[f] = arr;
    });

    var firstRun1 = -1, firstWarn = -1;
    for (var i = 0; i < T; i++) {
      if (firstRun1 < 0 && trace[i].run === 1) firstRun1 = i;
      if (firstWarn < 0 && Array.isArray(trace[i].warnings) && trace[i].warnings.length) firstWarn = i;
    }
    var notices = Array.isArray(record.notices) ? record.notices.filter(function (x) { return isObj(x); }) : [];

    // ---------- static drawing ----------
    var widthPx = n <= 16 ? 560 : Math.min(700, 560 + (n - 16) * 9);
    $('mv-stage').style.width = (widthPx + 2) + 'px';
    var LM = 0.75, TM = 0.25; // margins (cells): left/bottom carry the coordinate labels
    var root$ = svg('svg', {
      viewBox: [-LM, -TM, n + LM + TM, n + LM + TM].map(r3).join(' '),
      role: 'img', 'aria-label': 'maze replay', preserveAspectRatio: 'xMidYMid meet'
    });
    $('mv-maze-box').appendChild(root$);
    var lw = 0.07; // wall width in cells
    svg('rect', { x: 0, y: 0, width: n, height: n, fill: '#ffffff' }, root$);
    var gridD = '';
    for (var g = 1; g < n; g++) gridD += 'M' + g + ' 0V' + n + 'M0 ' + g + 'H' + n;
    svg('path', { d: gridD, stroke: '#eef0f3', 'stroke-width': 0.025, fill: 'none' }, root$);
    if (!maze) svg('text', { x: n / 2, y: n - 0.7, 'font-size': Math.max(0.45, n / 26), fill: '#d1d5db', 'text-anchor': 'middle', 'font-weight': 700 }, root$).textContent = 'maze hidden';
    var lo = Math.floor(n / 2) - 1;
    svg('rect', { x: lo, y: n - lo - 2, width: 2, height: 2, fill: '#fde68a', 'fill-opacity': 0.65 }, root$);
    svg('rect', { x: 0, y: n - 1, width: 1, height: 1, fill: '#bbf7d0', 'fill-opacity': 0.8 }, root$);
    var lbl = svg('text', { x: 0.08, y: n - 0.72, 'font-size': 0.22, fill: '#15803d', 'font-weight': 700 }, root$);
    lbl.textContent = 'S';
    var labels = svg('g', { 'font-size': n > 20 ? 0.42 : 0.3, fill: '#9ca3af', 'text-anchor': 'middle' }, root$);
    var lstep = n > 20 ? 2 : 1;
    for (var li = 0; li < n; li += lstep) {
      svg('text', { x: X(li), y: n + 0.5, 'dominant-baseline': 'middle' }, labels).textContent = String(li);
      svg('text', { x: -0.38, y: Y(li), 'dominant-baseline': 'middle' }, labels).textContent = String(li);
    }

    // heat map: one rect per cell, updated incrementally
    var heatLayer = svg('g', { id: 'heat-layer' }, root$);
    var heatRects = new Array(n * n), heatNow = new Uint16Array(n * n);
    for (var hx = 0; hx < n; hx++) for (var hy = 0; hy < n; hy++) {
      heatRects[hx * n + hy] = svg('rect', { x: hx, y: n - hy - 1, width: 1, height: 1, fill: '#ef4444', 'fill-opacity': 0 }, heatLayer);
    }

    // bot debug layer (below the real walls so the maze stays readable)
    var debugLayer = svg('g', { id: 'debug-layer' }, root$);
    var dbgFillG = svg('g', {}, debugLayer);
    var dbgPath = svg('path', { fill: 'none', stroke: '#c026d3', 'stroke-width': 0.06, 'stroke-dasharray': '0.02 0.12', 'stroke-linecap': 'round', 'stroke-linejoin': 'round', 'stroke-opacity': 0.9 }, debugLayer);
    var dbgWalls = svg('path', { fill: 'none', stroke: '#c026d3', 'stroke-width': 0.06, 'stroke-dasharray': '0.16 0.1' }, debugLayer);
    var dbgTextG = svg('g', { 'text-anchor': 'middle', 'dominant-baseline': 'central', fill: '#6b7280', stroke: '#ffffff', 'stroke-width': 0.05, 'paint-order': 'stroke' }, debugLayer);
    var dbgFills = new Array(n * n), dbgTexts = new Array(n * n);
    var fillNow = new Array(n * n).fill(''), valNow = new Array(n * n).fill('');

    // the real walls
    var wallD = '';
    if (maze) {
      var open = maze.open;
      for (var x = 0; x < n; x++) for (var y = 0; y < n; y++) {
        var v = open[x * n + y];
        if (y < n - 1 && (!(v & 1) || !(open[x * n + y + 1] & 4))) wallD += 'M' + x + ' ' + (n - y - 1) + 'h1';
        if (x < n - 1 && (!(v & 2) || !(open[(x + 1) * n + y] & 8))) wallD += 'M' + (x + 1) + ' ' + (n - y - 1) + 'v1';
      }
    }
    svg('path', { d: wallD, stroke: '#1f2937', 'stroke-width': lw, 'stroke-linecap': 'square', fill: 'none' }, root$);
    svg('rect', { x: 0, y: 0, width: n, height: n, stroke: '#111827', 'stroke-width': lw * 1.4, fill: 'none' }, root$);
    if (!maze) {
      var note = $('mv-maze-note');
      note.hidden = false;
      note.textContent = layoutStr == null ? 'maze hidden: only the outer wall is drawn' : 'maze layout unreadable: only the outer wall is drawn';
    }

    // optimal route, run 0 trail, run 1 path
    var optimalLayer = svg('g', { id: 'optimal-layer' }, root$);
    var opt = isObj(data.optimal) && Array.isArray(data.optimal.path) ? data.optimal.path.filter(function (p) { return isObj(p) && inGrid(p.x, p.y); }) : [];
    if (opt.length > 1) {
      svg('path', { d: opt.map(function (p, j) { return (j ? 'L' : 'M') + pt(p); }).join(''), fill: 'none', stroke: '#16a34a', 'stroke-opacity': 0.35, 'stroke-width': 0.34, 'stroke-linecap': 'round', 'stroke-linejoin': 'round' }, optimalLayer);
    }
    if (isObj(data.optimal) && isInt(data.optimal.steps)) $('mv-optimal-label').textContent = 'Optimal route (' + data.optimal.steps + ' steps)';
    else if (opt.length < 2) $('mv-optimal-label').textContent = 'Optimal route (none)';
    var trailLayer = svg('g', { id: 'trail-layer' }, root$);
    var trailPath = svg('path', { fill: 'none', stroke: '#7c3aed', 'stroke-width': 0.1, 'stroke-linecap': 'round', 'stroke-linejoin': 'round', 'stroke-opacity': 0.85 }, trailLayer);
    var run1Layer = svg('g', { id: 'run1-layer' }, root$);
    var run1Path = svg('path', { fill: 'none', stroke: '#2563eb', 'stroke-width': 0.13, 'stroke-linecap': 'round', 'stroke-linejoin': 'round' }, run1Layer);

    // sensor rays from the pre-step pose
    var sensorLayer = svg('g', { id: 'sensor-layer' }, root$);
    var ghost = svg('g', { display: 'none' }, sensorLayer);
    svg('path', { d: 'M0 -0.3L0.24 0.22L0 0.1L-0.24 0.22Z', fill: 'none', stroke: '#0d9488', 'stroke-width': 0.04, 'stroke-dasharray': '0.06 0.05' }, ghost);
    var rays = [0, 1, 2].map(function () {
      var gRay = svg('g', { display: 'none' }, sensorLayer);
      return {
        g: gRay,
        line: svg('line', { stroke: '#0d9488', 'stroke-width': 0.05, 'stroke-linecap': 'round' }, gRay),
        tick: svg('line', { stroke: '#0d9488', 'stroke-width': 0.1, 'stroke-linecap': 'round' }, gRay),
        label: svg('text', { 'font-size': 0.3, fill: '#0f766e', 'text-anchor': 'middle', 'dominant-baseline': 'central', stroke: '#fff', 'stroke-width': 0.07, 'paint-order': 'stroke', 'font-weight': 700 }, gRay)
      };
    });

    // the robot
    var robot = svg('g', { id: 'robot' }, root$);
    svg('circle', { r: 0.36, fill: '#ffffff', 'fill-opacity': 0.85, stroke: '#dc2626', 'stroke-width': 0.05 }, robot);
    svg('path', { d: 'M0 -0.27L0.2 0.18L0 0.08L-0.2 0.18Z', fill: '#dc2626', stroke: '#dc2626', 'stroke-width': 0.03, 'stroke-linejoin': 'round' }, robot);

    // ---------- per-step updates ----------
    var heatK = 0;
    function heatOpacity(c) { return c > 0 ? r3(0.08 + 0.5 * c / maxHeat) : 0; }
    if (inGrid(0, 0)) { heatNow[0] = 1; heatRects[0].setAttribute('fill-opacity', heatOpacity(1)); }
    function updateHeat(k) {
      var dirty = [];
      while (heatK < k) { heatDelta[heatK].forEach(function (idx) { heatNow[idx]++; dirty.push(idx); }); heatK++; }
      while (heatK > k) { heatK--; heatDelta[heatK].forEach(function (idx) { heatNow[idx]--; dirty.push(idx); }); }
      dirty.forEach(function (idx) { heatRects[idx].setAttribute('fill-opacity', heatOpacity(heatNow[idx])); });
    }

    function drawSensors(k) {
      var s = k > 0 ? trace[k - 1] : null, P = k > 0 ? poses[k - 1] : null;
      var ok = s && Array.isArray(s.sensors) && s.sensors.length === 3 && s.sensors.every(function (v) { return isInt(v) && v >= 0; });
      ghost.setAttribute('display', ok ? 'inline' : 'none');
      rays.forEach(function (ray, j) {
        if (!ok) { ray.g.setAttribute('display', 'none'); return; }
        var d = DIRS[HEADINGS[(HEADINGS.indexOf(P.h) + 3 + j) % 4]];
        var len = Math.min(s.sensors[j], 2 * n) + 0.5;
        var x0 = X(P.x), y0 = Y(P.y), x1 = x0 + d[0] * len, y1 = y0 - d[1] * len;
        ray.g.setAttribute('display', 'inline');
        ray.line.setAttribute('x1', r3(x0 + d[0] * 0.3)); ray.line.setAttribute('y1', r3(y0 - d[1] * 0.3));
        ray.line.setAttribute('x2', r3(x1)); ray.line.setAttribute('y2', r3(y1));
        ray.tick.setAttribute('x1', r3(x1 - d[1] * 0.22)); ray.tick.setAttribute('y1', r3(y1 - d[0] * 0.22));
        ray.tick.setAttribute('x2', r3(x1 + d[1] * 0.22)); ray.tick.setAttribute('y2', r3(y1 + d[0] * 0.22));
        ray.label.setAttribute('x', r3(x1 - d[0] * 0.25 + d[1] * 0.22)); ray.label.setAttribute('y', r3(y1 + d[1] * 0.25 + d[0] * 0.22));
        ray.label.textContent = String(s.sensors[j]);
      });
      if (ok) ghost.setAttribute('transform', 'translate(' + pt(P) + ') rotate(' + HEADINGS.indexOf(P.h) * 90 + ')');
    }

    // debug layer: parsed lazily, drawn into pooled per-cell elements
    var dbgKey = null;
    function cellValue(v) {
      if (isNum(v)) return Number.isInteger(v) ? (Math.abs(v) < 1e6 ? String(v) : v.toExponential(0)) : String(parseFloat(v.toPrecision(3)));
      if (typeof v === 'string') return v.slice(0, 5);
      return null;
    }
    function drawDebug(k) {
      var src = {};
      DBG_FIELDS.forEach(function (f) { src[f] = dbgSrc[f][k]; });
      var key = DBG_FIELDS.map(function (f) { return src[f]; }).join(',');
      if (key === dbgKey) return;
      dbgKey = key;
      function field(f) { return src[f] >= 0 ? trace[src[f]].debug[f] : null; }
      var cap = 4 * n * n;
      // colours
      var fills = new Array(n * n).fill('');
      (field('colors') || []).slice(0, cap).forEach(function (e) {
        if (Array.isArray(e) && inGrid(e[0], e[1]) && typeof e[2] === 'string' && COLOR_RE.test(e[2])) fills[e[0] * n + e[1]] = e[2];
      });
      // cell values: the grid first, single cells override it
      var vals = new Array(n * n).fill('');
      var grid = field('grid');
      if (grid) for (var gx = 0; gx < Math.min(n, grid.length); gx++) {
        if (!Array.isArray(grid[gx])) continue;
        for (var gy = 0; gy < Math.min(n, grid[gx].length); gy++) { var gv = cellValue(grid[gx][gy]); if (gv !== null) vals[gx * n + gy] = gv; }
      }
      (field('cells') || []).slice(0, cap).forEach(function (e) {
        if (Array.isArray(e) && inGrid(e[0], e[1])) { var cv = cellValue(e[2]); if (cv !== null) vals[e[0] * n + e[1]] = cv; }
      });
      for (var idx = 0; idx < n * n; idx++) {
        var cx = Math.floor(idx / n), cy = idx % n;
        if (fills[idx] !== fillNow[idx]) {
          if (!dbgFills[idx]) dbgFills[idx] = svg('rect', { x: cx, y: n - cy - 1, width: 1, height: 1, 'fill-opacity': 0.45 }, dbgFillG);
          if (fills[idx]) { dbgFills[idx].setAttribute('fill', fills[idx]); dbgFills[idx].removeAttribute('display'); } else dbgFills[idx].setAttribute('display', 'none');
          fillNow[idx] = fills[idx];
        }
        if (vals[idx] !== valNow[idx]) {
          if (!dbgTexts[idx]) dbgTexts[idx] = svg('text', { x: X(cx), y: r3(Y(cy) + 0.02) }, dbgTextG);
          dbgTexts[idx].textContent = vals[idx];
          dbgTexts[idx].setAttribute('font-size', vals[idx].length <= 2 ? 0.3 : vals[idx].length === 3 ? 0.25 : 0.2);
          valNow[idx] = vals[idx];
        }
      }
      // believed walls: dashed, drawn just inside the cell on that side
      var wd = '', inset = 0.1;
      (field('walls') || []).slice(0, cap).forEach(function (e) {
        if (!Array.isArray(e) || !inGrid(e[0], e[1]) || !DIRS[e[2]]) return;
        var left = e[0], top = n - e[1] - 1;
        if (e[2] === 'up') wd += 'M' + left + ' ' + r3(top + inset) + 'h1';
        else if (e[2] === 'down') wd += 'M' + left + ' ' + r3(top + 1 - inset) + 'h1';
        else if (e[2] === 'left') wd += 'M' + r3(left + inset) + ' ' + top + 'v1';
        else wd += 'M' + r3(left + 1 - inset) + ' ' + top + 'v1';
      });
      dbgWalls.setAttribute('d', wd);
      var pd = '';
      (field('path') || []).slice(0, cap).forEach(function (e) {
        if (Array.isArray(e) && inGrid(e[0], e[1])) pd += (pd ? 'L' : 'M') + pt({ x: e[0], y: e[1] });
      });
      dbgPath.setAttribute('d', pd);
    }

    // ---------- side panel ----------
    var info = $('step-info'), dbgText = $('debug-text'), dbgSource = $('debug-source'), stderrBox = $('step-stderr');
    function row(label, value, cls) {
      info.appendChild(html('dt', null, label));
      var dd = html('dd', cls || null);
      if (value instanceof Node) dd.appendChild(value); else dd.textContent = value;
      info.appendChild(dd);
      return dd;
    }
    function pre(box, content, empty) {
      box.textContent = content || empty;
      box.classList.toggle('mv-empty', !content);
    }
    function poseText(p) { return '(' + p.x + ', ' + p.y + ') facing ' + p.h; }
    function renderPanel(k) {
      info.textContent = '';
      var p = poses[k];
      if (k === 0) {
        row('Step', T ? 'start, before step 1' : 'start (the trace is empty)');
        row('Pose', poseText(p));
      } else {
        var s = trace[k - 1], t = stepNo(k - 1);
        row('Step', 't = ' + t + ' of ' + T + ' · run ' + runOf(k - 1));
        row('Sensors', Array.isArray(s.sensors) ? 'left ' + text(s.sensors[0], 20) + ' · front ' + text(s.sensors[1], 20) + ' · right ' + text(s.sensors[2], 20) : '—');
        var a = isObj(s.action) ? s.action : {};
        row('Answer', a.reset === true ? 'reset' : 'rotation ' + (isNum(a.rotation) && a.rotation > 0 ? '+' : '') + text(a.rotation, 20) + '°, movement ' + text(a.movement, 20));
        var ev = typeof s.event === 'string' ? s.event : '';
        var evDd = row('Event', EVENT_LABELS[ev] || text(ev, 80) || '—', 'mv-ev-' + (EVENT_LABELS[ev] ? ev : 'other'));
        if (s.blocked === true) evDd.appendChild(html('span', 'mv-ev-blocked', ' · blocked by a wall'));
        row('Pose after', poseText(p));
        row('Answer time', ms(s.answer_us));
        row('CPU time', ms(s.cpu_us));
        if (inGrid(p.x, p.y) && runOf(k - 1) === 0) row('Run-0 visits here', String(heatNow[p.x * n + p.y]));
        var warns = Array.isArray(s.warnings) ? s.warnings : [];
        if (warns.length) {
          var wbox = document.createDocumentFragment();
          warns.slice(0, 50).forEach(function (w) {
            wbox.appendChild(html('div', 'mv-warn', isObj(w) ? (text(w.kind, 80) || 'warning') + (w.message != null ? ': ' + text(w.message, 500) : '') : text(w, 500)));
          });
          row('Warnings', wbox);
        }
        var here = notices.filter(function (x) { return x.step === t; });
        if (here.length) {
          var nbox = document.createDocumentFragment();
          here.slice(0, 20).forEach(function (x) { nbox.appendChild(html('div', 'mv-note', text(x.message, 500))); });
          row('Runner notes', nbox);
        }
      }
      var lines = k > 0 && Array.isArray(trace[k - 1].stderr) ? trace[k - 1].stderr.slice(0, 500).map(function (l) { return text(l, 4000); }) : [];
      pre(stderrBox, lines.join('\n'), stderrHidden ? HIDDEN_STDERR : 'no stderr output at this step');
      // debug text and where the shown debug came from
      var ti = dbgSrc.text[k];
      pre(dbgText, ti >= 0 ? text(trace[ti].debug.text, 20000) : '', 'no debug text');
      var groups = {};
      DBG_FIELDS.forEach(function (f) { var i = dbgSrc[f][k]; if (i >= 0) (groups[i] = groups[i] || []).push(f); });
      var keys = Object.keys(groups).map(Number).sort(function (x, y) { return y - x; });
      if (!keys.length) dbgSource.textContent = DBG_FIELDS.every(function (f) { return dbgSrc[f][T] < 0; }) ? '(none in this replay)' : '(none yet)';
      else if (keys.length === 1) dbgSource.textContent = '(from step ' + stepNo(keys[0]) + (keys[0] === k - 1 ? '' : ', sticky') + ')';
      else dbgSource.textContent = '(' + keys.map(function (i) { return groups[i].join('/') + ' from step ' + stepNo(i); }).join('; ') + ')';
    }

    // ---------- summary (top) ----------
    (function renderSummary() {
      $('mv-title').textContent = text(data.title, 300) || 'Match replay';
      var box = $('mv-summary');
      function item(label, value, cls) {
        var d = html('div', cls || null);
        d.appendChild(html('dt', null, label));
        var dd = html('dd');
        if (value instanceof Node) dd.appendChild(value); else dd.textContent = value;
        d.appendChild(dd);
        box.appendChild(d);
        return dd;
      }
      var st = text(record.status, 40) || 'unknown';
      item('Status', html('span', 'mv-badge ' + (st === 'finished' ? 'ok' : st === 'step_limit' ? 'warn' : 'bad'), st.replace(/_/g, ' ')));
      item('Score', isNum(record.score) ? record.score.toFixed(3) : 'did not finish');
      item('Run 0 steps', isNum(record.run0_steps) ? String(record.run0_steps) : '—');
      item('Run 1 steps', isNum(record.run1_steps) ? String(record.run1_steps) : '—');
      item('Total steps', isNum(record.total_steps) ? String(record.total_steps) : String(T));
      item('Maze', n + ' × ' + n + (isInt(record.seed) ? ' · seed ' + record.seed : ''));
      var err = isObj(record.error) ? record.error : null;
      if (err) {
        var msg = text(err.reason, 1000) || 'unknown failure';
        if (isInt(err.step)) msg += ' at step ' + err.step;
        var dd = item('Failure', msg, 'mv-failure');
        if (typeof err.line === 'string') dd.appendChild(html('div', null, 'line: ' + text(err.line, 300)));
        if (isObj(err.limit)) dd.appendChild(html('div', null, 'limit: ' + text(err.limit.name, 60) + ' ' + text(err.limit.value, 30) + ' ' + text(err.limit.unit, 20)));
        var fi = isInt(err.step) ? trace.findIndex(function (s, j) { return stepNo(j) === err.step; }) : -1;
        if (fi >= 0) {
          var show = html('button', 'mv-link', 'show step');
          show.type = 'button';
          show.addEventListener('click', function () { go(fi + 1); });
          dd.insertBefore(show, dd.firstChild.nextSibling);
        }
      }
      var list = $('mv-notes-list');
      notices.slice(0, 200).forEach(function (x) { list.appendChild(html('li', null, 'step ' + text(x.step, 20) + ': ' + text(x.message, 500))); });
      $('mv-notes').hidden = notices.length === 0;
      var tail = text(record.stderr_tail, 100000);
      pre($('mv-tail-text'), tail, stderrHidden ? HIDDEN_STDERR : 'no stderr output');
      if (T === 0 && tail) $('mv-tail').open = true;
    })();

    // ---------- state, controls ----------
    var cur = -1, playing = false, rafId = 0, lastTs = null, acc = 0;
    var btnPlay = $('btn-play'), btnBack = $('btn-back'), btnFwd = $('btn-forward'), slider = $('slider'), speedSel = $('speed');
    var btnRun1 = $('btn-run1'), btnWarn = $('btn-warning'), stepNum = $('mv-stepnum');
    slider.max = String(T);

    function setStep(k) {
      k = clamp(Math.round(Number(k)) || 0, 0, T);
      if (k === cur) return;
      cur = k;
      root.setAttribute('data-step', String(k));
      var p = poses[k];
      robot.setAttribute('data-x', String(p.x));
      robot.setAttribute('data-y', String(p.y));
      robot.setAttribute('data-heading', p.h);
      robot.setAttribute('transform', 'translate(' + pt(p) + ') rotate(' + HEADINGS.indexOf(p.h) * 90 + ')');
      trailPath.setAttribute('d', trailCount[k] > 1 ? trailPts.slice(0, trailCount[k]).join('') : '');
      run1Path.setAttribute('d', run1Count[k] > 1 ? run1Pts.slice(0, run1Count[k]).join('') : '');
      updateHeat(k);
      drawSensors(k);
      drawDebug(k);
      renderPanel(k);
      slider.value = String(k);
      stepNum.textContent = k + ' / ' + T;
      btnBack.disabled = k === 0;
      btnFwd.disabled = k === T;
    }
    function tick(ts) {
      if (!playing) return;
      if (lastTs === null) lastTs = ts;
      acc += Math.min(ts - lastTs, 250) / 1000 * BASE_RATE * (Number(speedSel.value) || 1);
      lastTs = ts;
      if (acc >= 1) {
        var adv = Math.floor(acc);
        acc -= adv;
        setStep(cur + adv);
        if (cur >= T) { stop(); return; }
      }
      rafId = requestAnimationFrame(tick);
    }
    function play() {
      if (T === 0 || playing) return;
      if (cur >= T) setStep(0);
      playing = true; lastTs = null; acc = 0;
      btnPlay.textContent = '❚❚ Pause';
      rafId = requestAnimationFrame(tick);
    }
    function stop() {
      playing = false;
      if (rafId) cancelAnimationFrame(rafId);
      rafId = 0;
      btnPlay.textContent = '▶ Play';
    }
    function toggle() { if (playing) stop(); else play(); }
    function go(k) { stop(); setStep(k); }

    btnPlay.addEventListener('click', toggle);
    btnBack.addEventListener('click', function () { go(cur - 1); });
    btnFwd.addEventListener('click', function () { go(cur + 1); });
    slider.addEventListener('input', function () { go(slider.value); });
    btnRun1.addEventListener('click', function () { go(firstRun1 + 1); });
    btnWarn.addEventListener('click', function () { go(firstWarn + 1); });
    btnRun1.disabled = firstRun1 < 0;
    btnWarn.disabled = firstWarn < 0;
    if (T === 0) [btnPlay, btnBack, btnFwd, slider, speedSel].forEach(function (c) { c.disabled = true; });

    $('btn-download').addEventListener('click', function () {
      var rec = Object.assign({}, record);
      if (rec.maze_layout == null && layoutStr !== null) rec.maze_layout = layoutStr;
      var blob = new Blob([JSON.stringify(rec)], { type: 'application/json' });
      var url = URL.createObjectURL(blob);
      var a = document.createElement('a');
      a.href = url;
      a.download = text(data.download_name, 200) || 'replay.json';
      a.style.display = 'none';
      document.body.appendChild(a);
      a.click();
      setTimeout(function () { URL.revokeObjectURL(url); a.remove(); }, 1000);
    });

    var layers = { trail: trailLayer, heat: heatLayer, run1: run1Layer, optimal: optimalLayer, sensors: sensorLayer, debug: debugLayer };
    Object.keys(layers).forEach(function (name) {
      var box = $('layer-' + name), layer = layers[name];
      function apply() { if (box.checked) layer.removeAttribute('display'); else layer.setAttribute('display', 'none'); }
      box.addEventListener('change', apply);
      apply();
    });

    document.addEventListener('keydown', function (e) {
      if (e.altKey || e.ctrlKey || e.metaKey || T === 0) return;
      var tg = e.target, tag = tg && tg.tagName;
      if (tg && (tg.isContentEditable || tag === 'TEXTAREA' || tag === 'SELECT' || (tag === 'INPUT' && tg.type !== 'range' && tg.type !== 'checkbox'))) return;
      var key = e.key;
      if (key === 'ArrowRight') go(cur + 1);
      else if (key === 'ArrowLeft') go(cur - 1);
      else if (key === 'Home') go(0);
      else if (key === 'End') go(T);
      else if (key === ' ' || key === 'Spacebar') toggle();
      else return;
      e.preventDefault();
    });
    // keep Space from also "clicking" a focused button or checkbox on key release
    document.addEventListener('keyup', function (e) {
      if ((e.key === ' ' || e.key === 'Spacebar') && e.target && (e.target.tagName === 'BUTTON' || e.target.type === 'checkbox') && root.contains(e.target)) e.preventDefault();
    });

    function hashStep() {
      var m = /(?:^#|[#&])step=(\d+)/.exec(location.hash || '');
      return m ? clamp(parseInt(m[1], 10), 0, T) : null;
    }
    window.addEventListener('hashchange', function () { var h = hashStep(); if (h !== null) go(h); });
    var start = hashStep();
    setStep(start === null ? 0 : start);

    // Called by the page with the replay and log the owner's token fetched.
    window.mazearenaViewer = {
      showStderr: function (steps, tail) {
        if (Array.isArray(steps)) {
          steps.forEach(function (s, i) { if (trace[i] && isObj(s) && Array.isArray(s.stderr)) trace[i].stderr = s.stderr; });
        }
        stderrHidden = false;
        pre($('mv-tail-text'), text(tail, 100000), 'no stderr output');
        renderPanel(cur);
      }
    };
  }

  function safeInit() {
    try { init(); } catch (e) {
      var root = document.getElementById('viewer');
      if (root) {
        var p = document.createElement('p');
        p.textContent = 'The replay viewer could not start: ' + (e && e.message ? e.message : String(e));
        root.insertBefore(p, root.firstChild);
      }
      if (window.console) console.error(e);
    }
  }
  if (document.readyState === 'loading') document.addEventListener('DOMContentLoaded', safeInit);
  else safeInit();
})();
