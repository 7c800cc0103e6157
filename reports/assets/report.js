// The comparison report's behaviour: interactive charts (Vega-Embed, inflated from the page itself) and the
// side-by-side 3D replay. Everything it needs is in the page; it makes no request.
"use strict";

async function inflate(id) {
  const text = document.getElementById(id).textContent.trim();
  const bytes = Uint8Array.from(atob(text), (c) => c.charCodeAt(0));
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("gzip"));
  return await new Response(stream).text();
}

let chartSpecs = null;
let runtime = null;

function loadRuntime() {
  if (!runtime) {
    runtime = (async () => {
      (0, eval)(await inflate("vega-runtime"));
      chartSpecs = JSON.parse(await inflate("chart-specs"));
    })();
  }
  return runtime;
}

async function drawCharts(root) {
  const pending = [...root.querySelectorAll("div.chart:not([data-drawn])")];
  if (!pending.length) return;
  await loadRuntime();
  for (const el of pending) {
    el.setAttribute("data-drawn", "1");
    const spec = chartSpecs[el.dataset.spec];
    const result = await window.vegaEmbed(el, spec, { actions: false, renderer: "svg", tooltip: { theme: "light" } });
    el.vegaView = result.view;
    el.setAttribute("data-ready", "1");
  }
}

function setupCharts() {
  const observer = new IntersectionObserver((entries) => {
    for (const e of entries) {
      if (e.isIntersecting) {
        observer.unobserve(e.target);
        drawCharts(e.target.parentElement);
      }
    }
  });
  document.querySelectorAll("div.chart").forEach((el) => observer.observe(el));
  document.querySelectorAll("details").forEach((d) =>
    d.addEventListener("toggle", () => { if (d.open) drawCharts(d); }));
}

class Replay {
  constructor(el) {
    this.el = el;
    this.data = JSON.parse(el.querySelector("script.replay-data").textContent);
    this.canvas = el.querySelector("canvas");
    this.slider = el.querySelector("input[type=range]");
    this.button = el.querySelector("button.play");
    this.clock = el.querySelector(".clock");
    this.frame = 0;
    this.timer = null;
    this.sheet = null;
    this.slider.addEventListener("input", () => this.load().then(() => this.show(Number(this.slider.value))));
    this.button.addEventListener("click", () => this.load().then(() => this.toggle()));
    const wide = el.querySelector("button.wide");
    if (wide) wide.addEventListener("click", () => {  // the frames scaled to the page's width, and back
      const on = el.classList.toggle("wide");
      wide.textContent = on ? "⤡ actual size" : "⤢ full width";
      wide.setAttribute("aria-pressed", String(on));
    });
    el.querySelectorAll("button.moment").forEach((b) => b.addEventListener("click", () =>
      this.load().then(() => { this.stop(); this.show(this.nearest(Number(b.dataset.t))); })));
    const details = el.closest("details");
    if (!details || details.open) this.load().then(() => this.show(0));
    else details.addEventListener("toggle", () => { if (details.open) this.load().then(() => this.show(this.frame)); });
  }

  // the frames (a large image once decoded) are decoded when the replay is first opened
  load() {
    if (!this.sheet) {
      this.sheet = new Image();
      this.loaded = new Promise((done) => { this.sheet.onload = done; });
      this.sheet.src = this.el.dataset.sheet;
      this.loaded.then(() => { this.el.dataset.loaded = "1"; });
    }
    return this.loaded;
  }

  nearest(t) {
    let best = 0;
    this.data.times.forEach((u, k) => { if (Math.abs(u - t) < Math.abs(this.data.times[best] - t)) best = k; });
    return best;
  }

  show(k) {
    const d = this.data;
    this.frame = Math.max(0, Math.min(d.times.length - 1, k));
    this.slider.value = String(this.frame);
    this.clock.textContent = `t = ${d.times[this.frame].toFixed(2)} s`;
    const ctx = this.canvas.getContext("2d");
    ctx.fillStyle = "#ffffff";
    ctx.fillRect(0, 0, this.canvas.width, this.canvas.height);
    d.backends.forEach((b, row) => {
      ctx.drawImage(this.sheet, this.frame * d.w, row * d.h, d.w, d.h, row * (d.w + d.gap), 0, d.w, d.h);
    });
    this.el.dataset.frame = String(this.frame);
  }

  toggle() { if (this.timer) this.stop(); else this.play(); }

  play() {
    const d = this.data;
    if (this.frame >= d.times.length - 1) this.show(0);
    const step = d.times.length > 1 ? (d.times[1] - d.times[0]) * 1000 : 100;
    this.button.textContent = "❚❚ pause";
    this.timer = setInterval(() => {
      if (this.frame >= d.times.length - 1) { this.stop(); return; }
      this.show(this.frame + 1);
    }, Math.max(step, 16));
  }

  stop() {
    if (this.timer) clearInterval(this.timer);
    this.timer = null;
    this.button.textContent = "▶ play";
  }
}

function setupReplays() {
  document.querySelectorAll("div.replay").forEach((el) => { el.replay = new Replay(el); });
}

setupReplays();
setupCharts();
