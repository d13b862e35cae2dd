// The pendant's client lint panel: GET /api/lint every LINT_POLL_MS, one row per finding
// (what a client did that a real controller answers differently); "Clear" sends DELETE.
// Plain JavaScript, no library; separate from pendant.js so that the two evolve apart.
"use strict";
(function () {
  const LINT_POLL_MS = 1000;  // findings change at the pace of a client's mistakes, not of ticks
  const $ = (id) => document.getElementById(id);
  const lint = { findings: [], polls: 0 };
  window.pendantLint = lint;  // for debugging and the browser test

  function escapeHtml(s) {
    return String(s).replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" }[c]));
  }

  function render(doc) {
    lint.findings = doc.findings;
    const body = $("lint-findings");
    $("lint-count").textContent = doc.findings.length ? "(" + doc.findings.length + ")" : "";
    if (!doc.findings.length) {
      body.innerHTML = '<tr><td colspan="5" class="yes">none: no client did anything a robot would answer differently</td></tr>';
      return;
    }
    body.innerHTML = doc.findings.map((f) =>
      "<tr><td><b>" + escapeHtml(f.code) + "</b></td><td>" + f.count + "</td><td>" +
      Number(f.first_s).toFixed(3) + " s</td><td>" + escapeHtml(f.connection) + "</td><td>" +
      escapeHtml(f.reference) + "</td></tr>" +
      '<tr><td colspan="5" class="small">' + escapeHtml(f.text) +
      '<br><span class="yes">fix:</span> ' + escapeHtml(f.remedy) + "</td></tr>").join("");
  }

  async function refresh(method) {
    try {
      const resp = await fetch("/api/lint", { method: method || "GET" });
      if (resp.ok) { render(await resp.json()); lint.polls += 1; }
    } catch (e) { /* the simulator is gone: the feed's reconnect says so */ }
  }

  window.addEventListener("load", () => {
    $("btn-lint-clear").addEventListener("click", () => refresh("DELETE"));
    refresh();
    setInterval(refresh, LINT_POLL_MS);
  });
})();
