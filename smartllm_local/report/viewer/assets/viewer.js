// The run viewer's script: draws the run embedded in this page (#run-data) with the DOM and SVG alone.
// Written for this project; no library, no network. Views: the run (summary and task list) and a task
// (why it failed, its team, goals, timeline, map, stages and plan), chosen by the URL's #fragment.
"use strict";
(function () {
  const DATA = JSON.parse(document.getElementById("run-data").textContent);
  const TEXTS = DATA.texts || [];
  const SVG_NS = "http://www.w3.org/2000/svg";
  const PALETTE = ["#0969da", "#bf3989", "#1a7f37", "#bc4c00", "#8250df", "#0e8a8a", "#9a6700", "#57606a",
                   "#cf222e", "#4d2d00"];
  const filters = { category: "", status: "", feasible: "", text: "" };
  let showOnMap = () => {};  // the task view's map marks where the robots stood at a chosen action

  // ------------------------------------------------------------------ helpers

  function el(tag, attrs, ...children) {
    const node = document.createElement(tag);
    setAttrs(node, attrs);
    append(node, children);
    return node;
  }

  function sv(tag, attrs, ...children) {
    const node = document.createElementNS(SVG_NS, tag);
    setAttrs(node, attrs);
    append(node, children);
    return node;
  }

  function setAttrs(node, attrs) {
    for (const [key, value] of Object.entries(attrs || {})) {
      if (value === null || value === undefined || value === false) continue;
      if (key === "text") node.textContent = value;
      else if (key === "html") node.innerHTML = value;
      else if (key.startsWith("on")) node.addEventListener(key.slice(2), value);
      else node.setAttribute(key, value);
    }
  }

  function append(node, children) {
    for (const child of children.flat()) {
      if (child === null || child === undefined || child === false) continue;
      node.append(child instanceof Node ? child : document.createTextNode(String(child)));
    }
  }

  function escapeHtml(text) {
    return String(text).replace(/&/g, "&amp;").replace(/</g, "&lt;").replace(/>/g, "&gt;");
  }

  function num(value, digits = 2) {
    return value === null || value === undefined ? "n/a" : Number(value).toFixed(digits);
  }

  function pill(status) {
    return el("span", { class: "pill " + status, text: status });
  }

  function palette(keys, offset = 0) {
    const colors = {};
    keys.forEach((key, k) => { colors[key] = PALETTE[(k + offset) % PALETTE.length]; });
    return colors;
  }

  function objectType(objectId) {
    return objectId ? objectId.split("|")[0] : "";
  }

  // Python-like plans: comments, strings, keywords, numbers, skills (capitalised calls) and functions.
  const TOKENS = /(#[^\n]*)|("(?:[^"\\\n]|\\.)*"|'(?:[^'\\\n]|\\.)*')|\b(def|for|in|if|else|elif|return|pass|and|or|not|None|True|False|import|from|as|while|with)\b|\b(\d+(?:\.\d+)?)\b|\b([A-Z][A-Za-z0-9]*)(?=\()|\b([a-z_][A-Za-z0-9_]*)(?=\()/g;
  const TOKEN_CLASSES = [null, "com", "str", "kw", "numlit", "skill", "fn"];

  function highlight(code) {
    let html = "";
    let last = 0;
    code.replace(TOKENS, (match, ...groups) => {
      const offset = groups[groups.length - 2];
      html += escapeHtml(code.slice(last, offset));
      const which = groups.slice(0, 6).findIndex((g) => g !== undefined) + 1;
      html += `<span class="${TOKEN_CLASSES[which]}">${escapeHtml(match)}</span>`;
      last = offset + match.length;
      return match;
    });
    return html + escapeHtml(code.slice(last));
  }

  function codeBlock(code, highlighted) {
    return el("pre", highlighted ? { html: highlight(code || "") } : { text: code || "" });
  }

  // ------------------------------------------------------------------ routing

  function route() {
    const app = document.getElementById("app");
    app.replaceChildren();
    showOnMap = () => {};
    try {
      draw(app);
    } catch (error) {  // a view that cannot be drawn says so rather than leave the page blank
      console.error(error);
      app.append(el("div", { class: "why" }, el("p", { text: "This view could not be drawn (" + error + "). " +
        "Everything the page knows is in its run-data script, as JSON; the run folder holds the same files." })));
    }
  }

  function draw(app) {
    const hash = decodeURIComponent(location.hash.slice(1));
    const only = DATA.kind === "plan" && !hash ? "task/" + DATA.tasks[0].id : hash;  // a plan: its one task
    if (only.startsWith("task/")) {
      const task = DATA.tasks.find((t) => t.id === only.slice(5));
      if (task) { app.append(taskView(task)); window.scrollTo(0, 0); return; }
      app.append(el("p", { class: "banner", text: `This run has no task ${only.slice(5)}: its tasks are below.` }));
    }
    app.append(runView());
  }

  function header() {
    const parts = [DATA.label];
    if (DATA.model) parts.push(DATA.model);
    if (DATA.method) parts.push(DATA.method);
    document.getElementById("run-title").textContent = parts.join(" · ");
    const missing = DATA.missing || [];
    const banner = document.getElementById("missing");
    banner.hidden = missing.length === 0;
    banner.replaceChildren(...missing.map((m) => el("p", { text: m })));
  }

  // ------------------------------------------------------------------ the run

  function runView() {
    const box = el("div", { id: "run-view" });
    box.append(el("h1", { text: DATA.kind === "plan" ? "Plan " + DATA.label : "Run " + DATA.label }));
    box.append(runFacts());
    if (DATA.summary) box.append(summaryView(DATA.summary));
    box.append(el("h2", { text: "Tasks" }), taskList());
    return box;
  }

  function runFacts() {
    const facts = el("dl", { class: "kv" });
    const add = (key, value) => { if (value) facts.append(el("dt", { text: key }), el("dd", { text: value })); };
    add("folder", DATA.folder);
    add("model", DATA.model);
    add("method", DATA.method);
    add("started", DATA.started);
    add("versions", Object.entries(DATA.versions || {}).map(([k, v]) => `${k} ${v}`).join(", "));
    const given = Object.entries(DATA.arguments || {}).filter(([, v]) => v !== null && v !== false && v !== "auto");
    add("arguments", given.map(([k, v]) => `${k}=${Array.isArray(v) ? v.join(",") : v}`).join("  "));
    return facts;
  }

  function summaryView(summary) {
    const box = el("section", { id: "summary" });
    box.append(el("h2", { text: "Summary (Table I: feasible tasks per category)" }));
    const head = el("tr", {}, el("th", { text: "category" }), el("th", { class: "num", text: "tasks" }),
      el("th", { class: "num", text: "errors" }), el("th", { class: "num", text: "refused" }),
      summary.metrics.map((m) => el("th", { class: "num", text: m })));
    const rows = summary.rows.map((row) => el("tr", {}, el("td", { text: row.category }),
      el("td", { class: "num", text: row.tasks }), el("td", { class: "num", text: row.errors }),
      el("td", { class: "num", text: row.refused }),
      summary.metrics.map((m) => el("td", { class: "num", text: num(row[m]) }))));
    box.append(el("table", { id: "table-one" }, el("thead", {}, head), el("tbody", {}, rows)));
    const inf = summary.infeasible;
    if (inf && inf.tasks) {
      box.append(el("p", { text: `Infeasible tasks: ${inf.refused} of ${inf.tasks} correctly refused (by model ` +
        `${inf["by model"]}, by grammar ${inf["by grammar"]}, by rule ${inf["by rule"]}); ${inf.errors} error(s).` }));
    }
    const stages = Object.entries(summary.bending || {});
    if (stages.length) {
      box.append(el("h2", { text: "How far the grammar bent the model" }));
      box.append(el("table", { id: "bending" }, el("thead", {}, el("tr", {}, el("th", { text: "stage" }),
        el("th", { class: "num", text: "model's choices" }), el("th", { class: "num", text: "likeliest refused" }),
        el("th", { class: "num", text: "mean log-prob" }), el("th", { class: "num", text: "lines completed" }))),
      el("tbody", {}, stages.map(([stage, b]) => el("tr", {}, el("td", { text: stage }),
        el("td", { class: "num", text: b.choices }), el("td", { class: "num", text: num(100 * b.refused_share, 1) + "%" }),
        el("td", { class: "num", text: num(b.mean_logprob, 3) }), el("td", { class: "num", text: b.completed_lines }))))));
    }
    box.append(stageTimes(summary.stages || {}));
    return box;
  }

  function stageTimes(costs) {
    const parts = ["decomposition", "coalition", "allocation", "execution"].filter((p) => costs[p]);
    const box = el("div", { id: "stage-times" }, el("h2", { text: "Time per stage (seconds per task)" }));
    if (!parts.length) return box.appendChild(el("p", { class: "muted", text: "no stage timed" })) && box;
    const colors = palette(parts);
    const total = parts.reduce((sum, p) => sum + costs[p].share, 0) || 1;
    const width = 700;
    const chart = sv("svg", { class: "summary-bars", width: width, height: 28, viewBox: `0 0 ${width} 28` });
    let x = 0;
    for (const part of parts) {
      const w = (costs[part].share / total) * width;
      chart.append(sv("rect", { x: x, y: 2, width: Math.max(w, 0.5), height: 24, fill: colors[part] },
        sv("title", { text: `${part}: ${num(costs[part].share)} s per task` })));
      x += w;
    }
    box.append(chart, el("div", { class: "legend" }, parts.map((p) => el("span", {},
      el("span", { class: "swatch", style: `background:${colors[p]}` }),
      `${p} ${num(costs[p].share)} s` + (costs[p].prompt !== undefined ? ` (prompt ${Math.round(costs[p].prompt)} tok, ` +
        `generated ${Math.round(costs[p].generated)} tok)` : "")))));
    if (costs.task) box.append(el("p", { class: "muted", text: `${num(costs.task.seconds)} s per task, ` +
      `${num(costs.task.total, 1)} s in all, over ${costs.task.tasks} task(s)` }));
    return box;
  }

  function taskList() {
    const box = el("section", { id: "tasks" });
    const categories = [...new Set(DATA.tasks.map((t) => t.category).filter(Boolean))];
    const statuses = [...new Set(DATA.tasks.map((t) => t.status))];
    const select = (name, label, options) => el("label", {}, label, el("select", {
      id: "filter-" + name,
      onchange: (e) => { filters[name] = e.target.value; fill(); },
    }, el("option", { value: "", text: "all" }), options.map(([value, text]) =>
      el("option", { value: value, text: text, selected: filters[name] === value ? "selected" : null }))));
    const count = el("span", { class: "count" });
    const tally = {};
    DATA.tasks.forEach((t) => { tally[t.status] = (tally[t.status] || 0) + 1; });
    box.append(el("p", { class: "legend", id: "tally" }, Object.entries(tally).map(([status, n]) =>
      el("button", { "data-status": status, title: "show only these", onclick: () => {
        filters.status = status;
        box.querySelector("#filter-status").value = status;
        fill();
      } }, pill(status), ` ${n}`))));
    box.append(el("div", { class: "filters" },
      select("category", "category", categories.map((c) => [c, c])),
      select("status", "outcome", statuses.map((s) => [s, s])),
      select("feasible", "feasibility", [["yes", "feasible"], ["no", "infeasible"]]),
      el("label", {}, "search", el("input", { type: "search", id: "filter-text", value: filters.text,
        placeholder: "id or instruction", oninput: (e) => { filters.text = e.target.value.toLowerCase(); fill(); } })),
      count));
    const body = el("tbody");
    const table = el("table", { id: "task-table" }, el("thead", {}, el("tr", {},
      ["task", "category", "outcome", "SR", "GCR", "Exe", "trans.", "s", "instruction", "why"].map((h) =>
        el("th", { class: ["SR", "GCR", "Exe", "trans.", "s"].includes(h) ? "num" : null, text: h })))), body);
    box.append(table);
    function fill() {
      const shown = visibleTasks();
      body.replaceChildren(...shown.map(taskRow));
      count.textContent = `${shown.length} of ${DATA.tasks.length} task(s)`;
    }
    fill();
    return box;
  }

  function visibleTasks() {
    return DATA.tasks.filter((t) =>
      (!filters.category || t.category === filters.category) &&
      (!filters.status || t.status === filters.status) &&
      (!filters.feasible || (filters.feasible === "yes") === Boolean(t.feasible)) &&
      (!filters.text || (t.id + " " + t.instruction).toLowerCase().includes(filters.text)));
  }

  function taskRow(task) {
    const o = task.outcome || {};
    return el("tr", { "data-id": task.id, "data-status": task.status, "data-category": task.category,
      onclick: () => { location.hash = "task/" + encodeURIComponent(task.id); } },
    el("td", {}, el("a", { href: "#task/" + encodeURIComponent(task.id), text: task.id })),
    el("td", { text: task.category + (task.feasible ? "" : " (infeasible)") }),
    el("td", {}, pill(task.status)),
    el("td", { class: "num", text: num(o.SR) }), el("td", { class: "num", text: num(o.GCR) }),
    el("td", { class: "num", text: num(o.Exe) }), el("td", { class: "num", text: o.transitions ?? "" }),
    el("td", { class: "num", text: o.seconds ?? "" }),
    el("td", { text: task.instruction }),
    el("td", { class: "muted", text: (task.why || [])[0] || "" }));
  }

  // ------------------------------------------------------------------ a task

  function taskView(task) {
    const box = el("div", { id: "task-view", "data-id": task.id });
    const shown = visibleTasks();
    const at = shown.findIndex((t) => t.id === task.id);
    const link = (t, text) => t ? el("a", { href: "#task/" + encodeURIComponent(t.id), text: text }) :
      el("span", { class: "muted", text: text });
    box.append(el("div", { class: "nav" }, el("a", { href: "#", text: "← all tasks" }),
      link(shown[at - 1], "‹ previous"), link(shown[at + 1], "next ›")));
    box.append(el("h1", {}, task.id, " ", pill(task.status)));
    box.append(el("p", { id: "instruction" }, el("strong", { text: task.instruction || "(instruction unknown)" }),
      el("span", { class: "muted", text: `  ${task.category || ""}${task.feasible ? "" : ", infeasible"} · ` +
        `${task.floor_plan || "no floor plan"}` })));
    const reasons = task.why || [];
    box.append(el("div", { class: "why" + (reasons.length ? "" : " ok"), id: "why" },
      reasons.length ? reasons.map((r) => el("p", { text: r })) : el("p", { text: "succeeded: every goal met" })));
    for (const notice of task.notices || []) box.append(el("p", { class: "muted", text: "notice: " + notice }));
    const left = el("div", {}, metrics(task), team(task), conditions(task));
    const right = el("div", {}, el("h2", { text: "Map (top-down)" }), mapView(task));
    box.append(el("div", { class: "grid" }, left, right));
    box.append(el("h2", { text: "Timeline (a lane per robot)" }), timelineView(task));
    box.append(el("h2", { text: "Stages" }), stagesView(task));
    if (task.allocated) box.append(el("h2", { text: "Allocated plan" }), codeBlock(task.allocated, true));
    return box;
  }

  function metrics(task) {
    const o = task.outcome;
    if (!o) return el("p", { class: "muted", text: "no metrics: the task was not scored" });
    const names = ["SR", "TCR", "GCR", "RU", "Exe", "Speed"];
    return el("table", { id: "metrics" }, el("thead", {}, el("tr", {}, names.map((n) => el("th", { class: "num", text: n })),
      el("th", { class: "num", text: "transitions" }), el("th", { class: "num", text: "ticks" }),
      el("th", { class: "num", text: "seconds" }))),
    el("tbody", {}, el("tr", {}, names.map((n) => el("td", { class: "num", text: num(o[n]) })),
      el("td", { class: "num", text: o.transitions ?? "" }), el("td", { class: "num", text: o.ticks ?? "" }),
      el("td", { class: "num", text: o.seconds ?? "" }))));
  }

  function team(task) {
    return el("div", {}, el("h2", { text: "Team" }), el("table", { id: "team" },
      el("thead", {}, el("tr", {}, ["robot", "name", "mass capacity (kg)", "skills"].map((h) => el("th", { text: h })))),
      el("tbody", {}, task.team.map((r) => el("tr", {}, el("td", { text: r.id }), el("td", { text: r.name }),
        el("td", { class: "num", text: r.mass ?? "?" }),
        el("td", { class: "muted", text: (r.skills || []).join(", ") || "unknown" }))))));
  }

  function conditions(task) {
    const box = el("div", {}, el("h2", { text: "Goal conditions at the end" }));
    const list = (task.trace && task.trace.conditions) || [];
    if (!list.length) {
      box.append(el("p", { class: "muted", text: task.trace ? "the task has no goal conditions to judge by" :
        "not known: the plan did not run" }));
      return box;
    }
    box.append(el("ul", { class: "conditions", id: "conditions" },
      list.map((c) => el("li", { class: c.met ? "met" : "unmet", text: c.condition + (c.met ? "" : " (not met)") }))));
    return box;
  }

  function stagesView(task) {
    const box = el("div", { id: "stages" });
    if (!task.stages.length) box.append(el("p", { class: "muted", text: "no stage ran (or none was saved)" }));
    for (const stage of task.stages) {
      const t = stage.timings || {};
      const facts = [t.prompt_tokens !== undefined ? `${t.prompt_tokens} prompt tokens` : "",
        t.generated_tokens !== undefined ? `${t.generated_tokens} generated` : "",
        t.seconds !== undefined ? `${num(t.seconds)} s` : ""].filter(Boolean).join(", ");
      const part = el("div", { class: "stage", "data-stage": stage.name },
        el("h3", {}, stage.name, el("span", { class: "muted", text: facts ? "  " + facts : "" })));
      if (stage.refusal) part.append(el("p", { class: "why", text: "refused: " + stage.refusal }));
      if (stage.error) part.append(el("p", { class: "why", text: "error: " + stage.error }));
      part.append(codeBlock(stage.output, stage.name !== "coalition"));
      if ((stage.candidates || []).length) part.append(candidatesView(stage.candidates, task.outcome || {}));
      const fold = (label, text) => text ? el("details", {}, el("summary", { text: label }),
        el("pre", { text: text })) : null;
      append(part, [fold("prompt", TEXTS[stage.prompt]), fold("grammar", TEXTS[stage.grammar]),
        fold("raw output", stage.raw), fold("timings", JSON.stringify(t, null, 2))]);
      box.append(part);
    }
    return box;
  }

  // The decompositions written when the planner keeps several: each one's check (the stated goals its dry run
  // meets, its failed calls), its score, and whether it meets the task's own goals (measured after the run).
  function candidatesView(candidates, outcome) {
    const measured = Object.fromEntries((outcome.candidates || []).map((c) => [c.candidate, c.meets_task_goals]));
    const yesNo = (v) => v === true ? "yes" : v === false ? "no" : "—";
    return el("details", { class: "candidates", open: "open" }, el("summary", { text: `${candidates.length} ` +
      `candidates (the chosen one is above)` + (outcome.pass_at_n != null ? `; any meets the task's goals: ` +
      yesNo(outcome.pass_at_n) : "") }),
    el("table", {}, el("thead", {}, el("tr", {}, ["#", "chosen", "temperature", "stated goals met", "failed calls",
      "idle sub-tasks", "mean log-prob", "score", "meets the task's goals", "output"].map((h) => el("th", { text: h })))),
    el("tbody", {}, candidates.map((c) => {
      const check = c.check || {};
      return el("tr", { "data-candidate": c.candidate, class: c.chosen ? "chosen" : null },
        el("td", { class: "num", text: c.candidate }), el("td", { text: c.chosen ? "✔" : "" }),
        el("td", { class: "num", text: num(c.temperature) }),
        el("td", { class: "num", text: c.check ? `${check.met}/${check.goals}` : "—" }),
        el("td", { class: "num", text: c.check ? `${check.failed}/${check.calls}` : "—" }),
        el("td", { class: "num", text: c.check ? check.idle : "—" }),
        el("td", { class: "num", text: num(c.mean_logprob, 3) }), el("td", { class: "num", text: num(c.score, 3) }),
        el("td", { text: yesNo(measured[c.candidate]) }),
        el("td", {}, el("details", {}, el("summary", { text: c.refusal ? "refused" : c.error ? "error" : "plan" }),
          codeBlock(c.output || c.refusal || c.error || "", true))));
    }))));
  }

  // ------------------------------------------------------------------ timeline

  function lanesOf(task) {
    const ids = task.team.map((r) => r.id);
    for (const a of (task.trace && task.trace.actions) || []) {
      for (const r of a.robots) if (!ids.includes(r)) ids.push(r);
    }
    return ids;
  }

  function timelineView(task) {
    const box = el("div", {});
    const actions = (task.trace && task.trace.actions) || [];
    if (!task.trace) {
      box.append(el("p", { class: "muted", text: "no timeline: the plan did not run (" + task.status + ")" }));
      return box;
    }
    const lanes = lanesOf(task);
    const ticks = Math.max(task.trace.ticks || 0, ...actions.map((a) => a.tick + 1), 1);
    const subtasks = [...new Set(actions.map((a) => a.subtask))];
    const colors = palette(subtasks, 5);  // not the robots' colours (the map's): a bar's colour is its sub-task
    const labelW = 110, laneH = 36, step = Math.max(10, Math.min(48, 1100 / ticks));
    const width = labelW + ticks * step + 20, height = lanes.length * laneH + 30;
    const chart = sv("svg", { id: "timeline", width: width, height: height, viewBox: `0 0 ${width} ${height}` });
    const names = Object.fromEntries(task.team.map((r) => [r.id, r.name]));
    lanes.forEach((id, k) => {
      chart.append(sv("g", { class: "lane", "data-robot": id },
        sv("rect", { x: 0, y: k * laneH, width: width, height: laneH, fill: k % 2 ? "#fff" : "#f6f8fa" }),
        sv("text", { x: 6, y: k * laneH + laneH / 2 + 4, "font-size": 12, text: `${id} ${names[id] || ""}` })));
    });
    const every = Math.ceil(40 / step);
    for (let t = 0; t <= ticks; t += every) {
      chart.append(sv("text", { x: labelW + t * step, y: height - 10, "font-size": 10, fill: "#59636e", text: t }));
    }
    const detail = el("p", { id: "action-detail", class: "muted", text: "click a bar for its action; the map " +
      "then shows where the robots stood" });
    actions.forEach((a, i) => {
      const bar = sv("g", { class: "bar" + (a.success ? "" : " failed"), "data-index": i, "data-subtask": a.subtask,
        onclick: () => select(i) });
      const words = `tick ${a.tick} · ${a.subtask} · ${a.skill}(${a.objects.join(", ")}) by ${a.robots.join(", ")}` +
        (a.success ? " · ok" : ` · FAILED: ${a.errorMessage}`);
      for (const r of a.robots) {
        const y = lanes.indexOf(r) * laneH + 5;
        const x = labelW + a.tick * step;
        bar.append(sv("rect", { x: x, y: y, width: step - 1, height: laneH - 10, rx: 2, fill: colors[a.subtask] }));
        if (step >= 40) {
          bar.append(sv("text", { x: x + 3, y: y + laneH / 2, "font-size": 10, fill: "#fff", "pointer-events": "none",
            text: a.skill.replace(/Object$/, "").slice(0, Math.floor((step - (a.success ? 4 : 14)) / 6.5)) }));
        }
        if (!a.success) bar.append(sv("text", { class: "fail-mark", x: x + step - 12, y: y + laneH / 2 + 4, text: "✘" }));
      }
      bar.append(sv("title", { text: words }));
      chart.append(bar);
    });
    function select(i) {
      chart.querySelectorAll(".bar.selected").forEach((b) => b.classList.remove("selected"));
      chart.querySelector(`.bar[data-index="${i}"]`).classList.add("selected");
      const a = actions[i];
      detail.textContent = `tick ${a.tick} · ${a.subtask} · ${a.skill}(${a.objects.join(", ")}) by robot(s) ` +
        `${a.robots.join(", ")} → ${a.action || "no action sent"} ${a.objectId || ""}: ` +
        (a.success ? "succeeded" : "failed: " + a.errorMessage);
      showOnMap(i);
    }
    box.append(el("div", { class: "timeline-box" }, chart), detail,
      el("div", { class: "legend" }, subtasks.map((s) => el("span", {},
        el("span", { class: "swatch", style: `background:${colors[s]}` }), s)),
      el("span", {}, el("span", { class: "swatch", style: "border:2.5px solid #cf222e" }), "failed action")));
    return box;
  }

  // ------------------------------------------------------------------ map

  function mapView(task) {
    const box = el("div", {});
    const floor = DATA.floors[task.floor_plan];
    if (!task.trace) {
      box.append(el("p", { class: "muted", text: "no map: the plan did not run" }));
      return box;
    }
    const actions = task.trace.actions || [];
    if (!floor && !actions.some((a) => a.positions)) {
      box.append(el("p", { class: "muted", text: "no map: the trace holds no positions (a run made before they " +
        "were recorded, or a world that has none)" }));
      return box;
    }
    const lanes = lanesOf(task);
    const colors = palette(lanes);
    const scale = 60;
    const P = (x, z) => [x * scale, -z * scale];
    const paths = robotPaths(task, lanes);
    const points = [...((floor && floor.cells) || []), ...((floor && floor.landmarks) || []).map((l) => [l.x, l.z]),
      ...Object.values(paths).flat(), ...actions.filter((a) => a.objectPosition).map((a) => a.objectPosition)];
    if (!points.length) points.push([0, 0]);
    const xs = points.map((p) => p[0]), zs = points.map((p) => p[1]);
    const pad = 0.6;
    const [x0, y0] = P(Math.min(...xs) - pad, Math.max(...zs) + pad);
    const [x1, y1] = P(Math.max(...xs) + pad, Math.min(...zs) - pad);
    const chart = sv("svg", { id: "map", viewBox: `${x0} ${y0} ${x1 - x0} ${y1 - y0}`, width: "100%",
      style: `max-height:34rem;aspect-ratio:${(x1 - x0) / (y1 - y0)}` });
    if (floor && floor.cells.length) {
      const h = 0.125 * scale;
      const d = floor.cells.map(([x, z]) => { const [px, py] = P(x, z); return `M${px - h} ${py - h}h${2 * h}v${2 * h}h${-2 * h}z`; });
      chart.append(sv("path", { class: "cells", d: d.join("") }));
    }
    const targets = new Set(actions.map((a) => a.objectId));
    const named = new Set();  // a type is named once: ten cabinets' labels would hide the floor
    for (const l of (floor && floor.landmarks) || []) {
      if (l.type === "Floor" || targets.has(l.id)) continue;
      const [px, py] = P(l.x, l.z);
      chart.append(sv("rect", { class: "landmark", x: px - 5, y: py - 5, width: 10, height: 10 },
        sv("title", { text: l.id })));
      if (!named.has(l.type)) chart.append(sv("text", { class: "landmark-label", x: px + 7, y: py + 3, text: l.type }));
      named.add(l.type);
    }
    const seen = new Set();
    for (const a of actions) {
      if (!a.objectPosition || seen.has(a.objectId)) continue;
      seen.add(a.objectId);
      const [px, py] = P(...a.objectPosition);
      chart.append(sv("circle", { class: "target", cx: px, cy: py, r: 7, fill: "#fb8f44" },
        sv("title", { text: a.objectId })));
      chart.append(sv("text", { x: px + 9, y: py - 6, "font-size": 12, "font-weight": 600, text: objectType(a.objectId) }));
    }
    lanes.forEach((id) => {
      const route = paths[id] || [];
      if (!route.length) return;
      const pts = route.map((p) => P(...p));
      chart.append(sv("polyline", { class: "path", "data-robot": id, stroke: colors[id],
        points: pts.map((p) => p.join(",")).join(" ") }, sv("title", { text: `robot ${id}'s path` })));
      chart.append(sv("circle", { cx: pts[0][0], cy: pts[0][1], r: 6, fill: "#fff", stroke: colors[id], "stroke-width": 3 },
        sv("title", { text: `robot ${id} starts here` })));
      const end = pts[pts.length - 1];
      chart.append(sv("circle", { cx: end[0], cy: end[1], r: 6, fill: colors[id] }, sv("title", { text: `robot ${id} ends here` })));
    });
    for (const a of actions) {
      if (a.success || !a.positions) continue;
      const [px, py] = P(...a.positions[0]);
      chart.append(sv("text", { class: "fail-mark", x: px - 6, y: py + 6, "font-size": 18, text: "✘" },
        sv("title", { text: `tick ${a.tick}: ${a.skill} failed: ${a.errorMessage}` })));
    }
    const here = sv("g", { id: "map-here" });
    chart.append(here);
    showOnMap = (index) => {
      here.replaceChildren();
      const at = positionsAt(task, lanes, index);
      for (const id of lanes) {
        if (!at[id]) continue;
        const [px, py] = P(...at[id]);
        here.append(sv("circle", { class: "here", cx: px, cy: py, r: 10, fill: colors[id], opacity: 0.8 }));
      }
      const a = actions[index];
      if (a.objectPosition) {
        const [px, py] = P(...a.objectPosition);
        here.append(sv("circle", { cx: px, cy: py, r: 13, fill: "none", stroke: "#000", "stroke-width": 2.5 }));
      }
    };
    box.append(el("div", { class: "map-box" }, chart), el("div", { class: "legend" },
      lanes.map((id) => el("span", {}, el("span", { class: "swatch", style: `background:${colors[id]}` }), `robot ${id}`)),
      el("span", {}, el("span", { class: "swatch", style: "background:#fb8f44;border-radius:50%" }), "objects acted on"),
      el("span", { class: "muted", text: "○ start ● end ✘ failed action" })));
    return box;
  }

  function robotPaths(task, lanes) {
    const paths = {};
    const start = task.start || [];
    lanes.forEach((id, k) => { paths[id] = start[k] ? [start[k]] : []; });
    for (const a of task.trace.actions || []) {
      (a.positions || []).forEach((p, k) => {
        const route = paths[a.robots[k]] || (paths[a.robots[k]] = []);
        const last = route[route.length - 1];
        if (!last || last[0] !== p[0] || last[1] !== p[1]) route.push(p);
      });
    }
    return paths;
  }

  function positionsAt(task, lanes, index) {
    const at = {};
    const start = task.start || [];
    lanes.forEach((id, k) => { if (start[k]) at[id] = start[k]; });
    task.trace.actions.slice(0, index + 1).forEach((a) => (a.positions || []).forEach((p, k) => { at[a.robots[k]] = p; }));
    return at;
  }

  header();
  window.addEventListener("hashchange", route);
  route();
  performance.mark("viewer-drawn");  // how long the page took to draw, by its own clock (the browser tests report it)
})();
