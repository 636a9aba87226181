/* The image viewer and sortable tables of a gibench report (index.html).
 * Embedded into the gibench binary at build time (harness/CMakeLists.txt)
 * and written inline into every index.html, so that the page works from
 * file:// with no server and no network.
 *
 * Data: the JSON in <script id="gib-data"> lists, per reference set, its
 * images (references and runs): a tonemapped PNG, the linear HDR data in a
 * JS file beside it (GIB_HDR(key, width, height, base64 RGBE), loaded with
 * a <script src>, which file:// allows where fetch does not), and error maps
 * (PNG heat maps whose colour bar sits right of the map).
 *
 * Keys (in the viewer under the mouse, else the first): left/right or
 * digits pick the image, b makes it the comparison image, space swaps the
 * two, i/f/s/w single, flip, side by side, wipe; m cycles image and error
 * maps; + and - change the exposure; 0 resets zoom and pan. */
(function () {
  'use strict';

  var hdrCallbacks = {};
  /* Called by each image's .js file: decodes RGBE into linear RGB floats. */
  window.GIB_HDR = function (key, w, h, b64) {
    var bin = atob(b64), n = w * h, f = new Float32Array(n * 3);
    for (var i = 0; i < n; i++) {
      var e = bin.charCodeAt(4 * i + 3);
      if (!e) continue;
      var s = Math.pow(2, e - 136);
      f[3 * i] = (bin.charCodeAt(4 * i) + 0.5) * s;
      f[3 * i + 1] = (bin.charCodeAt(4 * i + 1) + 0.5) * s;
      f[3 * i + 2] = (bin.charCodeAt(4 * i + 2) + 0.5) * s;
    }
    var cbs = hdrCallbacks[key] || [];
    delete hdrCallbacks[key];
    cbs.forEach(function (cb) { cb({ w: w, h: h, data: f }); });
  };

  var hdrCache = {};
  function loadHdr(path, done) {
    if (hdrCache[path] !== undefined) {
      if (hdrCache[path] === 'loading') hdrCallbacks[path].push(done);
      else done(hdrCache[path]);
      return;
    }
    hdrCache[path] = 'loading';
    hdrCallbacks[path] = [function (d) { hdrCache[path] = d; }, done];
    var s = document.createElement('script');
    s.src = path;
    s.onerror = function () {
      var cbs = hdrCallbacks[path] || [];
      delete hdrCallbacks[path];
      hdrCache[path] = null;
      cbs.forEach(function (cb) { cb(null); });
    };
    document.head.appendChild(s);
  }

  var pngCache = {};
  /* A PNG drawn into a canvas (for its pixels); done(canvas or null). */
  function loadPng(path, done) {
    var c = pngCache[path];
    if (c && c.ready) { done(c.canvas); return; }
    if (c) { c.waiting.push(done); return; }
    c = pngCache[path] = { ready: false, canvas: null, waiting: [done] };
    var img = new Image();
    img.onload = function () {
      var cv = document.createElement('canvas');
      cv.width = img.naturalWidth;
      cv.height = img.naturalHeight;
      cv.getContext('2d').drawImage(img, 0, 0);
      c.canvas = cv;
      finish();
    };
    img.onerror = finish;
    function finish() {
      c.ready = true;
      c.waiting.forEach(function (cb) { cb(c.canvas); });
      c.waiting = [];
    }
    img.src = path;
  }

  /* The core's display transform: 2^EV * v, clamped, sRGB-encoded. */
  function toSrgb8(v) {
    v = v > 0 ? (v < 1 ? v : 1) : 0;
    v = v <= 0.0031308 ? 12.92 * v : 1.055 * Math.pow(v, 1 / 2.4) - 0.055;
    return Math.round(v * 255);
  }

  function tonemap(hdr, ev) {
    var cv = document.createElement('canvas');
    cv.width = hdr.w;
    cv.height = hdr.h;
    var ctx = cv.getContext('2d'), id = ctx.createImageData(hdr.w, hdr.h), k = Math.pow(2, ev);
    var lut = new Uint8Array(4097);
    for (var i = 0; i <= 4096; i++) lut[i] = toSrgb8(i / 4096);
    for (var p = 0, n = hdr.w * hdr.h; p < n; p++) {
      for (var c = 0; c < 3; c++) {
        var v = hdr.data[3 * p + c] * k;
        id.data[4 * p + c] = lut[Math.round((v > 1 ? 1 : v > 0 ? v : 0) * 4096)];
      }
      id.data[4 * p + 3] = 255;
    }
    ctx.putImageData(id, 0, 0);
    return cv;
  }

  function el(tag, attrs, text) {
    var e = document.createElement(tag);
    for (var k in attrs || {}) e.setAttribute(k, attrs[k]);
    if (text !== undefined) e.textContent = text;
    return e;
  }

  function fmt(v) {
    if (Math.abs(v) >= 1000 || (v !== 0 && Math.abs(v) < 0.001)) return v.toExponential(3);
    return v.toPrecision(4);
  }

  var viewers = [], active = null;

  function Viewer(root, set) {
    var self = this;
    this.root = root;
    this.set = set;
    this.a = set.images.length > 1 ? 1 : 0; /* the first run or matched reference */
    this.b = 0;                              /* the full-GI reference */
    this.mode = 'single';
    this.view = 'image';                     /* 'image' or an error map's name */
    this.flipped = false;
    this.ev = set.exposure || 0;
    this.zoom = 1;
    this.cx = null;
    this.cy = null;
    this.wipe = 0.5;
    this.hdr = {};
    this.tone = {};
    this.png = {};
    this.maps = {};
    this.mouse = null;

    root.tabIndex = 0;
    var bar = el('div', { 'class': 'gib-bar' });
    this.list = el('div', { 'class': 'gib-list' });
    set.images.forEach(function (im, i) {
      var btn = el('button', { type: 'button', 'data-index': String(i), title: im.title || im.label },
                   (i < 9 ? (i + 1) + ': ' : '') + im.label);
      btn.addEventListener('click', function (ev) {
        if (ev.shiftKey) self.b = i; else self.a = i;
        self.flipped = false;
        self.update();
      });
      self.list.appendChild(btn);
    });
    root.appendChild(this.list);

    var modes = el('span', { 'class': 'gib-group' });
    [['single', 'image (i)'], ['flip', 'flip (f)'], ['side', 'side by side (s)'], ['wipe', 'wipe (w)']].forEach(function (m) {
      var b = el('button', { type: 'button', 'data-mode': m[0] }, m[1]);
      b.addEventListener('click', function () { self.setMode(m[0]); });
      modes.appendChild(b);
    });
    bar.appendChild(modes);

    this.bsel = el('select', { 'class': 'gib-bsel', title: 'the image compared with (b, or shift-click)' });
    set.images.forEach(function (im, i) { self.bsel.appendChild(el('option', { value: String(i) }, im.label)); });
    this.bsel.addEventListener('change', function () { self.b = +self.bsel.value; self.update(); });
    var bl = el('label', {}, 'compare with ');
    bl.appendChild(this.bsel);
    bar.appendChild(bl);

    this.views = el('span', { 'class': 'gib-group' });
    bar.appendChild(this.views);

    var evl = el('label', { title: 'exposure in stops, applied to the linear HDR data (+ and -)' }, 'exposure ');
    this.evIn = el('input', { type: 'range', min: '-10', max: '10', step: '0.5', value: String(this.ev), 'class': 'gib-ev' });
    this.evOut = el('span', { 'class': 'gib-evval' });
    this.evIn.addEventListener('input', function () { self.setEv(+self.evIn.value); });
    evl.appendChild(this.evIn);
    evl.appendChild(this.evOut);
    bar.appendChild(evl);

    var reset = el('button', { type: 'button', title: 'reset zoom and pan (0)' }, 'fit');
    reset.addEventListener('click', function () { self.resetView(); });
    bar.appendChild(reset);
    root.appendChild(bar);

    this.stage = el('div', { 'class': 'gib-stage' });
    this.canvases = [el('canvas', { 'class': 'gib-canvas' }), el('canvas', { 'class': 'gib-canvas' })];
    this.caps = [el('div', { 'class': 'gib-cap' }), el('div', { 'class': 'gib-cap' })];
    this.panes = [0, 1].map(function (k) {
      var p = el('div', { 'class': 'gib-pane' });
      p.appendChild(self.canvases[k]);
      p.appendChild(self.caps[k]);
      self.stage.appendChild(p);
      return p;
    });
    this.colorbar = el('canvas', { 'class': 'gib-colorbar' });
    this.stage.appendChild(this.colorbar);
    root.appendChild(this.stage);

    this.wipeIn = el('input', { type: 'range', min: '0', max: '1', step: '0.001', value: '0.5', 'class': 'gib-wipe',
                                title: 'wipe position' });
    this.wipeIn.addEventListener('input', function () { self.wipe = +self.wipeIn.value; self.draw(); });
    root.appendChild(this.wipeIn);

    this.readout = el('div', { 'class': 'gib-readout' }, 'move the mouse over the image for pixel values');
    root.appendChild(this.readout);
    this.info = el('div', { 'class': 'gib-info' });
    root.appendChild(this.info);
    root.appendChild(el('div', { 'class': 'gib-help' },
      'keys: \u2190 \u2192 or 1\u20139 image, b compare with this one, space swap, i/f/s/w image/flip/side by side/wipe, ' +
      'm error maps, + \u2212 exposure, 0 fit; mouse wheel zooms, drag pans (locked across images); shift-click picks the image compared with'));

    this.canvases.forEach(function (cv) {
      cv.addEventListener('wheel', function (ev) {
        ev.preventDefault();
        var r = cv.getBoundingClientRect(), t = self.xform(cv);
        var ix = (ev.clientX - r.left - t.ox) / t.s, iy = (ev.clientY - r.top - t.oy) / t.s;
        var f = ev.deltaY < 0 ? 1.25 : 0.8;
        self.zoom = Math.max(0.25, Math.min(64, self.zoom * f));
        var t2 = self.xform(cv);
        /* keep the pixel under the cursor in place */
        self.cx += ix - (ev.clientX - r.left - t2.ox) / t2.s;
        self.cy += iy - (ev.clientY - r.top - t2.oy) / t2.s;
        self.draw();
      }, { passive: false });
      var drag = null;
      cv.addEventListener('mousedown', function (ev) { drag = { x: ev.clientX, y: ev.clientY }; ev.preventDefault(); });
      window.addEventListener('mouseup', function () { drag = null; });
      cv.addEventListener('mousemove', function (ev) {
        var r = cv.getBoundingClientRect();
        if (drag) {
          var s = self.xform(cv).s;
          self.cx -= (ev.clientX - drag.x) / s;
          self.cy -= (ev.clientY - drag.y) / s;
          drag = { x: ev.clientX, y: ev.clientY };
          self.draw();
        }
        self.mouse = { cv: cv, x: ev.clientX - r.left, y: ev.clientY - r.top };
        self.showPixel();
      });
    });
    root.addEventListener('mouseenter', function () { active = self; });
    root.addEventListener('focus', function () { active = self; });
    window.addEventListener('resize', function () { self.layout(); self.draw(); });
    this.update();
  }

  Viewer.prototype.image = function (i) { return this.set.images[i]; };

  /* Loads what image i needs (HDR data, PNG, maps) and redraws when it comes. */
  Viewer.prototype.fetch = function (i) {
    var self = this, im = this.image(i);
    if (im.hdr && this.hdr[i] === undefined) {
      this.hdr[i] = 'loading';
      loadHdr(im.hdr, function (d) { self.hdr[i] = d; self.tone[i] = null; self.draw(); self.showPixel(); });
    }
    if (im.png && this.png[i] === undefined) {
      this.png[i] = 'loading';
      loadPng(im.png, function (c) { self.png[i] = c; self.draw(); });
    }
    (im.maps || []).forEach(function (m) {
      var key = i + '/' + m.name;
      if (self.maps[key] === undefined) {
        self.maps[key] = 'loading';
        loadPng(m.png, function (c) { self.maps[key] = c; self.draw(); });
      }
    });
  };

  /* The size of image i's picture (without a heat map's colour bar). */
  Viewer.prototype.size = function (i) {
    var h = this.hdr[i], p = this.png[i];
    if (h && h !== 'loading') return { w: h.w, h: h.h };
    if (p && p !== 'loading') return { w: p.width, h: p.height };
    return null;
  };

  /* What to draw for image i in the current view: a canvas and the area of it. */
  Viewer.prototype.source = function (i) {
    var sz = this.size(i);
    if (!sz) return null;
    var hasMap = (this.image(i).maps || []).some(function (x) { return x.name === this.view; }, this);
    if (this.view !== 'image' && hasMap) {
      var m = this.maps[i + '/' + this.view];
      return m && m !== 'loading' ? { cv: m, w: sz.w, h: sz.h } : null;
    }
    /* an image without that map (a reference) shows itself */
    var h = this.hdr[i];
    if (h && h !== 'loading') {
      if (!this.tone[i] || this.tone[i].ev !== this.ev) this.tone[i] = { ev: this.ev, cv: tonemap(h, this.ev) };
      return { cv: this.tone[i].cv, w: sz.w, h: sz.h };
    }
    var p = this.png[i];
    return p && p !== 'loading' ? { cv: p, w: sz.w, h: sz.h } : null;
  };

  Viewer.prototype.setMode = function (m) { this.mode = m; this.flipped = false; this.layout(); this.update(); };
  Viewer.prototype.setEv = function (ev) {
    this.ev = Math.max(-10, Math.min(10, ev));
    this.evIn.value = String(this.ev);
    this.draw();
    this.showPixel();
  };
  Viewer.prototype.resetView = function () { this.zoom = 1; this.cx = this.cy = null; this.draw(); };

  /* Canvas sizes from the page width: never wider than the viewer's box. */
  Viewer.prototype.layout = function () {
    var sz = this.size(this.a) || this.size(this.b) || { w: 1, h: 1 };
    var avail = Math.max(200, this.root.clientWidth - 110); /* room for the colour bar */
    var two = this.mode === 'side';
    /* at most 640 px, and short enough to leave the controls in view */
    var maxh = Math.max(320, Math.min(640, (window.innerHeight || 900) - 240));
    var w = Math.min(two ? Math.floor((avail - 12) / 2) : avail, 640);
    var h = Math.round(w * sz.h / sz.w);
    if (h > maxh) { w = Math.round(w * maxh / h); h = maxh; }
    var dpr = window.devicePixelRatio || 1;
    this.canvases.forEach(function (cv) {
      cv.width = Math.round(w * dpr);
      cv.height = Math.round(h * dpr);
      cv.style.width = w + 'px';
      cv.style.height = h + 'px';
    });
    this.panes[1].style.display = two ? '' : 'none';
    this.wipeIn.style.display = this.mode === 'wipe' ? '' : 'none';
    this.wipeIn.style.width = w + 'px';
  };

  /* Image to canvas (CSS pixels): x_css = ox + s * x_image. */
  Viewer.prototype.xform = function (cv) {
    var known = this.size(this.a) || this.size(this.b), sz = known || { w: 1, h: 1 };
    var W = parseFloat(cv.style.width) || cv.width, H = parseFloat(cv.style.height) || cv.height;
    /* the centre is set once an image's size is known (fit until then) */
    if (this.cx === null && known) { this.cx = sz.w / 2; this.cy = sz.h / 2; }
    var cx = this.cx === null ? sz.w / 2 : this.cx, cy = this.cy === null ? sz.h / 2 : this.cy;
    var s = Math.min(W / sz.w, H / sz.h) * this.zoom;
    return { s: s, ox: W / 2 - cx * s, oy: H / 2 - cy * s, W: W, H: H };
  };

  Viewer.prototype.paint = function (cv, i, clipFrom) {
    var ctx = cv.getContext('2d'), dpr = cv.width / (parseFloat(cv.style.width) || cv.width);
    var t = this.xform(cv), src = this.source(i);
    ctx.save();
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    if (clipFrom !== undefined) {
      ctx.beginPath();
      ctx.rect(clipFrom, 0, t.W - clipFrom, t.H);
      ctx.clip();
    } else {
      ctx.fillStyle = '#444';
      ctx.fillRect(0, 0, t.W, t.H);
    }
    if (src) {
      ctx.imageSmoothingEnabled = false;
      ctx.setTransform(dpr * t.s, 0, 0, dpr * t.s, dpr * t.ox, dpr * t.oy);
      ctx.drawImage(src.cv, 0, 0, src.w, src.h, 0, 0, src.w, src.h);
    }
    ctx.restore();
  };

  /* The colour bar of the shown error map: the part of the heat map right of
   * the picture, scaled by a whole factor to the canvas height. */
  Viewer.prototype.drawColorbar = function () {
    var cb = this.colorbar, i = this.flipped ? this.b : this.a, sz = this.size(i);
    var m = this.view !== 'image' ? this.maps[i + '/' + this.view] : null;
    if (!m || m === 'loading' || !sz || m.width <= sz.w) { cb.style.display = 'none'; return; }
    var bw = m.width - sz.w, bh = m.height;
    var H = parseFloat(this.canvases[0].style.height);
    var k = Math.max(1, Math.min(4, Math.floor(H / bh)));
    cb.width = bw * k;
    cb.height = bh * k;
    cb.style.width = bw * k + 'px';
    cb.style.height = bh * k + 'px';
    cb.style.display = '';
    var ctx = cb.getContext('2d');
    ctx.imageSmoothingEnabled = false;
    ctx.drawImage(m, sz.w, 0, bw, bh, 0, 0, bw * k, bh * k);
  };

  Viewer.prototype.draw = function () {
    var sz = this.size(this.a) || this.size(this.b), key = sz ? sz.w + 'x' + sz.h : '';
    if (!this.canvases[0].style.width || key !== this.laidFor) { this.laidFor = key; this.layout(); }
    var a = this.flipped ? this.b : this.a, b = this.flipped ? this.a : this.b;
    if (this.mode === 'side') {
      this.paint(this.canvases[0], this.a);
      this.paint(this.canvases[1], this.b);
      this.caps[0].textContent = this.image(this.a).label;
      this.caps[1].textContent = this.image(this.b).label;
    } else if (this.mode === 'wipe') {
      var cv = this.canvases[0], W = parseFloat(cv.style.width);
      this.paint(cv, this.a);
      this.paint(cv, this.b, this.wipe * W);
      var ctx = cv.getContext('2d'), dpr = cv.width / W;
      ctx.fillStyle = '#fff';
      ctx.fillRect(Math.round(this.wipe * W * dpr) - 1, 0, 2, cv.height);
      this.caps[0].textContent = 'left: ' + this.image(this.a).label + ' | right: ' + this.image(this.b).label;
    } else {
      this.paint(this.canvases[0], a);
      this.caps[0].textContent = this.image(a).label + (this.mode === 'flip' ? '  (space flips to ' + this.image(b).label + ')' : '');
    }
    this.drawColorbar();
    this.evOut.textContent = ' ' + (this.ev > 0 ? '+' : '') + this.ev.toFixed(1) + ' EV' +
      (this.hasHdr(a) ? '' : ' (no HDR data: PNG shown)');
  };

  Viewer.prototype.hasHdr = function (i) { var h = this.hdr[i]; return !!(h && h !== 'loading'); };

  /* Rebuilds the buttons' state and the view list, loads, redraws. */
  Viewer.prototype.update = function () {
    var self = this;
    this.fetch(this.a);
    this.fetch(this.b);
    Array.prototype.forEach.call(this.list.children, function (btn, i) {
      btn.classList.toggle('gib-a', i === self.a);
      btn.classList.toggle('gib-b', i === self.b);
    });
    Array.prototype.forEach.call(this.root.querySelectorAll('[data-mode]'), function (b) {
      b.classList.toggle('gib-on', b.getAttribute('data-mode') === self.mode);
    });
    this.bsel.value = String(this.b);
    /* the views: the image, and the error maps image A has */
    var names = ['image'].concat((this.image(this.a).maps || []).map(function (m) { return m.name; }));
    if (names.indexOf(this.view) < 0) this.view = 'image';
    this.views.textContent = '';
    names.forEach(function (n) {
      var b = el('button', { type: 'button', 'data-view': n, title: 'm cycles' }, n);
      b.classList.toggle('gib-on', n === self.view);
      b.addEventListener('click', function () { self.view = n; self.update(); });
      self.views.appendChild(b);
    });
    var im = this.image(this.a);
    this.info.textContent = im.info || '';
    this.layout();
    this.draw();
  };

  /* The value under the cursor: linear RGB of each shown image (HDR data)
   * and the displayed 8-bit sRGB. */
  Viewer.prototype.showPixel = function () {
    if (!this.mouse) return;
    var t = this.xform(this.mouse.cv);
    var x = Math.floor((this.mouse.x - t.ox) / t.s), y = Math.floor((this.mouse.y - t.oy) / t.s);
    var sz = this.size(this.a);
    if (!sz || x < 0 || y < 0 || x >= sz.w || y >= sz.h) { this.readout.textContent = 'outside the image'; return; }
    var self = this, parts = [], shown = this.mode === 'single' || this.mode === 'flip'
      ? [this.flipped ? this.b : this.a] : [this.a, this.b];
    shown.forEach(function (i) {
      var s = self.image(i).label + ': ', h = self.hdr[i];
      if (h && h !== 'loading') {
        var p = 3 * (y * h.w + x);
        s += 'linear ' + fmt(h.data[p]) + ' ' + fmt(h.data[p + 1]) + ' ' + fmt(h.data[p + 2]);
      }
      var src = self.source(i);
      if (src) {
        var d = src.cv.getContext('2d').getImageData(x, y, 1, 1).data;
        s += ' \u2192 shown ' + d[0] + ' ' + d[1] + ' ' + d[2];
      }
      parts.push(s);
    });
    this.readout.textContent = 'pixel ' + x + ', ' + y + ' \u2014 ' + parts.join(' | ');
    this.readout.setAttribute('data-pixel', x + ',' + y);
  };

  Viewer.prototype.key = function (ev) {
    var n = this.set.images.length, k = ev.key;
    if (k === 'ArrowRight') this.a = (this.a + 1) % n;
    else if (k === 'ArrowLeft') this.a = (this.a + n - 1) % n;
    else if (k >= '1' && k <= '9' && +k <= n) this.a = +k - 1;
    else if (k === 'b') this.b = this.a;
    else if (k === ' ') {
      if (this.mode === 'flip' || this.mode === 'single') { this.flipped = !this.flipped; this.draw(); this.showPixel(); return true; }
      var t = this.a; this.a = this.b; this.b = t;
    } else if (k === 'i') { this.setMode('single'); return true; }
    else if (k === 'f') { this.setMode('flip'); return true; }
    else if (k === 's') { this.setMode('side'); return true; }
    else if (k === 'w') { this.setMode('wipe'); return true; }
    else if (k === 'm') {
      var names = ['image'].concat((this.image(this.a).maps || []).map(function (m) { return m.name; }));
      this.view = names[(names.indexOf(this.view) + 1) % names.length];
    } else if (k === '+' || k === '=') { this.setEv(this.ev + 0.5); return true; }
    else if (k === '-') { this.setEv(this.ev - 0.5); return true; }
    else if (k === '0') { this.resetView(); return true; }
    else return false;
    this.flipped = false;
    this.update();
    this.showPixel();
    return true;
  };

  document.addEventListener('keydown', function (ev) {
    var t = ev.target && ev.target.tagName;
    if (t === 'INPUT' || t === 'SELECT' || t === 'TEXTAREA' || ev.ctrlKey || ev.metaKey || ev.altKey) return;
    var v = active || viewers[0];
    if (v && v.key(ev)) ev.preventDefault();
  });

  /* Sortable tables: a click on a header sorts by that column (numbers by
   * value, from data-v where given; again to reverse). */
  function sortable(table) {
    var heads = table.tHead ? table.tHead.rows[0].cells : [];
    Array.prototype.forEach.call(heads, function (th, col) {
      th.classList.add('gib-sort');
      th.title = 'sort';
      th.addEventListener('click', function () {
        var body = table.tBodies[0], rows = Array.prototype.slice.call(body.rows);
        var dir = th.getAttribute('data-dir') === 'asc' ? -1 : 1;
        Array.prototype.forEach.call(heads, function (h) { h.removeAttribute('data-dir'); });
        th.setAttribute('data-dir', dir > 0 ? 'asc' : 'desc');
        function key(r) {
          var c = r.cells[col];
          if (!c) return '';
          var s = c.hasAttribute('data-v') ? c.getAttribute('data-v') : c.textContent.trim();
          var v = parseFloat(s);
          return isNaN(v) || !/^[-+0-9.]/.test(s) ? s.toLowerCase() : v;
        }
        rows.sort(function (x, y) {
          var a = key(x), b = key(y);
          if (typeof a === 'number' && typeof b === 'number') return dir * (a - b);
          if (typeof a === 'number') return -1;
          if (typeof b === 'number') return 1;
          return dir * (a < b ? -1 : a > b ? 1 : 0);
        });
        rows.forEach(function (r) { body.appendChild(r); });
      });
    });
  }

  function start() {
    var node = document.getElementById('gib-data'), data = node ? JSON.parse(node.textContent) : { sets: [] };
    Array.prototype.forEach.call(document.querySelectorAll('.gib-viewer'), function (root) {
      var set = data.sets[+root.getAttribute('data-set')];
      if (set && set.images.length) viewers.push(new Viewer(root, set));
    });
    Array.prototype.forEach.call(document.querySelectorAll('table.sortable'), sortable);
    window.gibViewers = viewers; /* for the browser test and the console */
  }
  if (document.readyState === 'loading') document.addEventListener('DOMContentLoaded', start);
  else start();
})();
