/* medkit-replay HTML report: zoomable timeline, debounce counter traces, sortable tables.
   Vanilla and offline. Data come from the JSON in #medkit-data and reach the page only through
   textContent and setAttribute; nothing is ever parsed as HTML or evaluated. */
(function () {
  'use strict';
  var errors = [];
  function recordError(message) {
    errors.push(String(message));
    var box = document.getElementById('js-errors');
    if (box) { box.hidden = false; box.textContent = 'Script errors:\n' + errors.join('\n'); }
    document.body.dataset.jsErrors = String(errors.length);
  }
  window.addEventListener('error', function (e) { recordError(e.message || 'error'); });
  window.addEventListener('unhandledrejection', function (e) { recordError('rejection: ' + e.reason); });
  document.addEventListener('securitypolicyviolation', function (e) {
    recordError('blocked by the page policy: ' + e.violatedDirective + ' ' + e.blockedURI);
  });

  var DATA = JSON.parse(document.getElementById('medkit-data').textContent);
  var SVGNS = document.getElementById('svg-ns').namespaceURI;
  var D = Math.max(DATA.duration_s, 1e-3);
  var MAX_ZOOM = 2000;
  var CHART_H = 170, PAD_T = 16, PAD_B = 16;

  function el(tag, cls, text) {
    var e = document.createElement(tag);
    if (cls) e.className = cls;
    if (text !== undefined && text !== null) e.textContent = String(text);
    return e;
  }
  function sv(tag, attrs, text) {
    var e = document.createElementNS(SVGNS, tag);
    Object.keys(attrs).forEach(function (k) { e.setAttribute(k, String(attrs[k])); });
    if (text !== undefined) e.textContent = String(text);
    return e;
  }
  function decimals(step) { return Math.min(6, Math.max(0, -Math.floor(Math.log10(step) + 1e-9))); }
  function secs(t) { return t.toFixed(3) + ' s'; }

  /* ---- tooltip ---- */
  var tip = document.getElementById('tip');
  function placeTip(e) {
    var x = e.clientX + 14, y = e.clientY + 14;
    if (x + tip.offsetWidth > window.innerWidth - 8) x = e.clientX - tip.offsetWidth - 14;
    if (y + tip.offsetHeight > window.innerHeight - 8) y = e.clientY - tip.offsetHeight - 14;
    tip.style.left = Math.max(4, x) + 'px';
    tip.style.top = Math.max(4, y) + 'px';
  }
  function showTip(text, e) { tip.textContent = text; tip.hidden = false; placeTip(e); }
  document.addEventListener('mouseover', function (e) {
    var target = e.target && e.target.closest ? e.target.closest('[data-tip]') : null;
    if (target) showTip(target.getAttribute('data-tip'), e); else tip.hidden = true;
  });
  document.addEventListener('mousemove', function (e) { if (!tip.hidden) placeTip(e); });
  document.addEventListener('mouseleave', function () { tip.hidden = true; });

  /* ---- timeline: zoom = track width / viewport width; pan = native horizontal scroll ---- */
  var scroller = document.getElementById('tl-scroll');
  var inner = document.getElementById('tl-inner');
  var axis = document.getElementById('tl-axis');
  var grid = document.getElementById('tl-grid');
  var brush = document.getElementById('tl-brush');
  var rangeLabel = document.getElementById('tl-range');
  var rows = Array.prototype.slice.call(document.querySelectorAll('.fault-row'));
  var zoom = 1, pending = false, openRows = {};

  function labelW() { var l = document.querySelector('.fault-label'); return l ? l.offsetWidth : 300; }
  function viewW() { return Math.max(120, scroller.clientWidth - labelW()); }
  function trackW() { return viewW() * zoom; }
  function visible() {
    var a = scroller.scrollLeft / trackW() * D;
    return [a, Math.min(D, a + D / zoom)];
  }
  function setZoom(z, anchorT, anchorPx) {
    zoom = Math.min(MAX_ZOOM, Math.max(1, z));
    inner.style.width = (labelW() + viewW() * zoom) + 'px';
    scroller.scrollLeft = anchorT / D * trackW() - anchorPx;
    redrawNow();
  }
  function center() { var v = visible(); return (v[0] + v[1]) / 2; }
  function niceStep(raw) {
    var p = Math.pow(10, Math.floor(Math.log10(raw)));
    var m = raw / p;
    return (m <= 1 ? 1 : m <= 2 ? 2 : m <= 5 ? 5 : 10) * p;
  }
  function tickValues() {
    var v = visible();
    var step = niceStep((v[1] - v[0]) / Math.max(2, viewW() / 110));
    var values = [];
    var first = Math.ceil(v[0] / step - 1e-9);
    for (var k = first; k * step <= v[1] + step * 1e-6 && k - first < 400; k++) values.push(k * step);
    return { values: values, step: step, range: v };
  }
  function drawAxis() {
    var t = tickValues(), digits = decimals(t.step);
    var ticks = [], lines = [];
    t.values.forEach(function (value) {
      var pos = (value / D * 100) + '%';
      var tick = el('div', 'tick');
      tick.style.left = pos;
      tick.appendChild(el('span', null, value.toFixed(digits)));
      ticks.push(tick);
      var line = el('div', 'gl');
      line.style.left = pos;
      lines.push(line);
    });
    ticks.push(brush);
    axis.replaceChildren.apply(axis, ticks);
    grid.replaceChildren.apply(grid, lines);
    var fine = decimals(t.step / 10), v = t.range;
    rangeLabel.textContent = v[0].toFixed(fine) + ' – ' + v[1].toFixed(fine) + ' s' +
      (zoom > 1.001 ? '   ×' + zoom.toFixed(zoom < 10 ? 2 : 0) : '');
  }
  function redrawNow() {
    pending = false;
    drawAxis();
    Object.keys(openRows).forEach(function (i) { drawChart(openRows[i]); });
  }
  function redraw() { if (!pending) { pending = true; window.requestAnimationFrame(redrawNow); } }
  function trackX(e) { return e.clientX - axis.getBoundingClientRect().left; }
  function wheelZoom(e) {
    e.preventDefault();
    var px = Math.max(0, e.clientX - scroller.getBoundingClientRect().left - labelW());
    setZoom(zoom * (e.deltaY < 0 ? 1.25 : 0.8), (scroller.scrollLeft + px) / trackW() * D, px);
  }

  function initTimeline() {
    if (!scroller) return;
    var axisRow = axis.parentNode;
    axisRow.addEventListener('wheel', wheelZoom, { passive: false });
    scroller.addEventListener('wheel', function (e) {
      if (e.ctrlKey && !axisRow.contains(e.target)) wheelZoom(e);
    }, { passive: false });
    scroller.addEventListener('scroll', redraw);
    window.addEventListener('resize', function () { setZoom(zoom, center(), viewW() / 2); });
    var drag = null;
    axis.addEventListener('mousedown', function (e) {
      if (e.button !== 0) return;
      drag = { x0: trackX(e), x1: trackX(e) };
      e.preventDefault();
    });
    axis.addEventListener('mousemove', function (e) {
      var t = trackX(e) / trackW() * D;
      axis.setAttribute('data-tip', 't = ' + t.toFixed(3) + ' s from start');
      showTip(axis.getAttribute('data-tip'), e);
    });
    window.addEventListener('mousemove', function (e) {
      if (!drag) return;
      drag.x1 = trackX(e);
      brush.style.left = Math.min(drag.x0, drag.x1) + 'px';
      brush.style.width = Math.abs(drag.x1 - drag.x0) + 'px';
      brush.hidden = false;
    });
    window.addEventListener('mouseup', function () {
      if (!drag) return;
      var d = drag;
      drag = null;
      brush.hidden = true;
      if (Math.abs(d.x1 - d.x0) < 5) return;
      var a = Math.min(d.x0, d.x1) / trackW() * D, b = Math.max(d.x0, d.x1) / trackW() * D;
      setZoom(D / (b - a), a, 0);
    });
    document.querySelectorAll('[data-zoom]').forEach(function (button) {
      button.addEventListener('click', function () {
        var kind = button.getAttribute('data-zoom');
        if (kind === 'reset') setZoom(1, 0, 0);
        else setZoom(kind === 'in' ? zoom * 2 : zoom / 2, center(), viewW() / 2);
      });
    });
    scroller.addEventListener('click', function (e) {
      var row = e.target.closest('.fault-row');
      if (row) toggle(row);
    });
    scroller.addEventListener('keydown', function (e) {
      var row = e.target.closest ? e.target.closest('.fault-row') : null;
      if (row && (e.key === 'Enter' || e.key === ' ')) { e.preventDefault(); toggle(row); }
    });
    var filter = document.getElementById('tl-filter');
    filter.addEventListener('input', function () {
      var q = filter.value.trim().toLowerCase();
      rows.forEach(function (row) {
        var lane = DATA.lanes[+row.dataset.index];
        var hay = (lane.code + ' ' + lane.status + ' ' + lane.description + ' ' +
          lane.sources.join(' ') + ' ' + lane.clusters.join(' ')).toLowerCase();
        var gone = q !== '' && hay.indexOf(q) < 0;
        row.classList.toggle('gone', gone);
        var o = openRows[row.dataset.index];
        if (o) o.detail.classList.toggle('gone', gone);
      });
    });
    setZoom(1, 0, 0);
  }

  /* ---- per-fault detail: counter trace with thresholds, near misses ---- */
  function toggle(row) {
    var i = row.dataset.index;
    if (openRows[i]) {
      openRows[i].detail.remove();
      delete openRows[i];
      row.classList.remove('open');
      row.setAttribute('aria-expanded', 'false');
      return;
    }
    var lane = DATA.lanes[+i];
    var o = { lane: lane, detail: el('div', 'fault-detail'), body: el('div', 'detail-body'),
      axisBox: el('div', 'detail-axis'), plot: el('div', 'detail-plot') };
    var chart = el('div', 'detail-chart');
    chart.append(o.axisBox, o.plot);
    o.body.append(chart, chartLegend(lane), info(lane));
    o.detail.appendChild(o.body);
    o.detail.dataset.code = lane.code;
    row.after(o.detail);
    row.classList.add('open');
    row.setAttribute('aria-expanded', 'true');
    openRows[i] = o;
    drawChart(o);
  }
  function openFault(code, scroll) {
    var row = rows.find(function (r) { return r.dataset.code === code; });
    if (!row) return;
    row.classList.remove('gone');
    if (!openRows[row.dataset.index]) toggle(row);
    if (scroll) row.scrollIntoView({ block: 'center' });
  }
  function chartLegend(lane) {
    var p = el('div', 'chart-legend');
    p.append(el('b', null, 'Debounce counter'),
      ' after each accepted report (red dot FAILED, green dot PASSED, orange ring near miss); ' +
      'red dashed: confirmation threshold, green dashed: healing threshold. ');
    var n = lane.trace.length;
    p.append(n < lane.trace_count
      ? 'Downsampled: ' + n + ' of ' + lane.trace_count + ' reports drawn (lowest and highest per interval).'
      : n + ' report' + (n === 1 ? '' : 's') + '.');
    return p;
  }
  function kv(dl, key, value) {
    dl.append(el('dt', null, key), el('dd', null, value === null || value === '' ? '—' : value));
  }
  function info(lane) {
    var box = el('div', 'detail-info');
    var left = el('div'), right = el('div');
    var dl = el('dl', 'kv');
    kv(dl, 'fault', lane.code);
    kv(dl, 'status', lane.status + ', severity ' + lane.severity);
    kv(dl, 'description', lane.description);
    kv(dl, 'reporting sources', lane.sources.join(', '));
    kv(dl, 'occurrences', lane.occurrences);
    kv(dl, 'first / last', secs(lane.first_s) + ' / ' + secs(lane.last_s));
    kv(dl, 'last passed', lane.last_passed_s === null ? 'never' : secs(lane.last_passed_s));
    kv(dl, 'muted by', lane.muted_by);
    kv(dl, 'clusters', lane.clusters.join(', '));
    left.append(el('h4', null, 'Final state'), dl);
    right.append(el('h4', null, 'Near misses (' + lane.near_count + ')'));
    if (!lane.near.length) {
      right.append(el('p', 'muted-text', 'None: no FAILED report left this fault short of confirmation.'));
    } else {
      var best = lane.near.reduce(function (b, n) { return n[1] - n[2] < b[1] - b[2] ? n : b; });
      var gap = best[1] - best[2];
      right.append(el('p', 'closest', 'Closest: counter ' + best[1] + ' against threshold ' + best[2] +
        ' — ' + gap + ' FAILED report' + (gap === 1 ? '' : 's') + ' short, at ' + secs(best[0]) +
        ' from ' + best[4]));
      var table = el('table', 'near');
      var head = el('tr');
      ['t (s)', 'counter', 'threshold', 'short by', 'severity', 'source_id', 'status after']
        .forEach(function (h) { head.append(el('th', null, h)); });
      table.append(head);
      lane.near.forEach(function (n) {
        var tr = el('tr');
        [n[0].toFixed(3), n[1], n[2], n[1] - n[2], n[3], n[4], n[5]]
          .forEach(function (v) { tr.append(el('td', null, v)); });
        table.append(tr);
      });
      right.append(table);
      if (lane.near.length < lane.near_count) {
        right.append(el('p', 'cap-note', 'Showing ' + lane.near.length + ' of ' + lane.near_count + '.'));
      }
    }
    box.append(left, right);
    return box;
  }
  function drawChart(o) {
    var lane = o.lane, pts = lane.trace, w = viewW(), lw = labelW(), v = visible();
    o.body.style.width = scroller.clientWidth + 'px';
    o.plot.replaceChildren();
    o.axisBox.replaceChildren();
    if (!pts.length) {
      o.plot.append(el('p', 'chart-legend', 'No accepted report with a debounce counter for this fault.'));
      return;
    }
    var lo = 0, hi = 0;
    pts.forEach(function (p) { lo = Math.min(lo, p[1], p[2]); hi = Math.max(hi, p[1], p[3]); });
    lo -= 0.6; hi += 0.6;
    function X(t) { return Math.min(w + 10, Math.max(-10, (t - v[0]) / (v[1] - v[0]) * w)); }
    function Y(c) { return PAD_T + (hi - c) / (hi - lo) * (CHART_H - PAD_T - PAD_B); }
    function step(index, fromX) {
      var d = 'M' + fromX.toFixed(1) + ' ' + Y(pts[0][index]).toFixed(1);
      pts.forEach(function (p) { d += ' H' + X(p[0]).toFixed(1) + ' V' + Y(p[index]).toFixed(1); });
      return d + ' H' + X(D).toFixed(1);
    }
    var svg = sv('svg', { width: w, height: CHART_H, viewBox: '0 0 ' + w + ' ' + CHART_H });
    tickValues().values.forEach(function (t) {
      svg.append(sv('line', { x1: X(t), x2: X(t), y1: 0, y2: CHART_H, stroke: '#e4e7ec', 'stroke-dasharray': '3 3' }));
    });
    svg.append(sv('line', { x1: 0, x2: w, y1: Y(0), y2: Y(0), stroke: '#c2c7cf' }));
    svg.append(sv('path', { d: step(2, X(0)), fill: 'none', stroke: '#d64545', 'stroke-width': 1.5, 'stroke-dasharray': '6 4' }));
    svg.append(sv('path', { d: step(3, X(0)), fill: 'none', stroke: '#2b8a57', 'stroke-width': 1.5, 'stroke-dasharray': '6 4' }));
    svg.append(sv('path', { d: step(1, X(pts[0][0])), fill: 'none', stroke: '#2457c5', 'stroke-width': 2 }));
    var names = DATA.statuses;
    pts.forEach(function (p) {
      var x = X(p[0]);
      if (x < -5 || x > w + 5) return;
      svg.append(sv('circle', { cx: x, cy: Y(p[1]), r: 3.5, fill: p[4] ? '#2b8a57' : '#d64545',
        stroke: '#fff', 'data-tip': 't = ' + secs(p[0]) + '  ' + (p[4] ? 'PASSED' : 'FAILED') +
          '\ncounter ' + p[1] + ' (confirm at ≤ ' + p[2] + ', heal at ≥ ' + p[3] + ')' +
          '\nstatus after: ' + (names[p[5]] || '?') }));
    });
    lane.near.forEach(function (n) {
      var x = X(n[0]);
      if (x < -8 || x > w + 8) return;
      svg.append(sv('circle', { cx: x, cy: Y(n[1]), r: 7, fill: 'none', stroke: '#e08a00',
        'stroke-width': 2.5, 'data-tip': 'near miss at ' + secs(n[0]) + '\ncounter ' + n[1] +
          ', threshold ' + n[2] + ' (' + (n[1] - n[2]) + ' short)\n' + n[3] + ' from ' + n[4] +
          '\nstatus after: ' + n[5] }));
    });
    o.plot.append(svg);
    var last = pts[pts.length - 1];
    var ax = sv('svg', { width: lw, height: CHART_H });
    ax.append(sv('text', { x: 8, y: 12, 'font-size': 11, fill: '#667085' }, 'debounce counter'));
    var labels = [[last[2], 'confirm ≤ ' + last[2], '#b42318'], [last[3], 'heal ≥ ' + last[3], '#2b8a57']];
    labels.forEach(function (l) {
      ax.append(sv('text', { x: 8, y: Y(l[0]) + 4, 'font-size': 11, fill: l[2] }, l[1]));
    });
    var every = Math.max(1, Math.ceil((hi - lo) / 8));
    for (var c = Math.ceil(lo); c <= Math.floor(hi); c += every) {
      ax.append(sv('text', { x: lw - 8, y: Y(c) + 4, 'font-size': 10, fill: '#667085', 'text-anchor': 'end' }, c));
      ax.append(sv('line', { x1: lw - 5, x2: lw, y1: Y(c), y2: Y(c), stroke: '#9aa3af' }));
    }
    o.axisBox.append(ax);
  }

  /* ---- tables: click a header to sort, type to filter ---- */
  function sortTable(table, th) {
    var col = +th.dataset.col, numeric = th.classList.contains('num');
    var dir = th.classList.contains('asc') ? -1 : 1;
    table.tHead.querySelectorAll('th').forEach(function (h) { h.classList.remove('asc', 'desc'); });
    th.classList.add(dir === 1 ? 'asc' : 'desc');
    var body = table.tBodies[0];
    var keyed = Array.prototype.map.call(body.rows, function (r, i) {
      var cell = r.cells[col];
      var key = numeric ? (cell && cell.dataset.v !== undefined ? +cell.dataset.v : -Infinity)
        : (cell ? cell.textContent.toLowerCase() : '');
      return [key, i, r];
    });
    keyed.sort(function (a, b) { return a[0] < b[0] ? -dir : a[0] > b[0] ? dir : a[1] - b[1]; });
    keyed.forEach(function (k) { body.appendChild(k[2]); });
  }
  function initTables() {
    document.querySelectorAll('table.sortable').forEach(function (table) {
      table.tHead.addEventListener('click', function (e) {
        var th = e.target.closest('th');
        if (th) sortTable(table, th);
      });
    });
    document.querySelectorAll('input.filter').forEach(function (input) {
      var id = input.getAttribute('data-filter-for');
      var table = document.getElementById(id);
      var shown = Array.prototype.find.call(document.querySelectorAll('[data-shown-for]'),
        function (s) { return s.getAttribute('data-shown-for') === id; });
      input.addEventListener('input', function () {
        var q = input.value.trim().toLowerCase(), n = 0, all = table.tBodies[0].rows;
        Array.prototype.forEach.call(all, function (r) {
          var ok = q === '' || r.textContent.toLowerCase().indexOf(q) >= 0;
          r.classList.toggle('gone', !ok);
          if (ok) n++;
        });
        if (shown) shown.textContent = q === '' ? '' : n + ' of ' + all.length + ' rows match';
      });
    });
    document.addEventListener('click', function (e) {
      var link = e.target.closest ? e.target.closest('td.code, .code-link') : null;
      if (link) openFault(link.getAttribute('data-open') || link.textContent, true);
    });
  }

  try {
    initTimeline();
    initTables();
    var hash = window.location.hash;
    if (hash.indexOf('#fault=') === 0) openFault(decodeURIComponent(hash.slice(7)), false);
    document.body.dataset.rows = String(rows.length);
    document.body.dataset.rendered = errors.length ? 'error' : 'ok';
  } catch (err) {
    recordError(err && err.stack ? err.stack : err);
    document.body.dataset.rendered = 'error';
  }
})();
