// SPDX-License-Identifier: Apache-2.0
// The cab page: polls /api/machine (the broker's latest values of every board) and draws one
// card per board, left to right along the boom; Start asks for a confirmation first, Stop
// never waits; the dose at full weed cover goes to every board; each card shows the board's
// latest live-view picture. Plain JavaScript, no libraries.
"use strict";

const POLL_MS = 250;
const CONFIRM_MS = 5000;
let confirmTimer = null;
// One <img> per board, kept across redraws so a picture loads only when a new one came.
const pictures = new Map();

function pictureOf(name, picture) {
  let img = pictures.get(name);
  if (!img) {
    img = el("img", { class: "picture", alt: `${name}: live view with the weed overlay` });
    pictures.set(name, img);
  }
  if (img.dataset.seq !== String(picture.seq)) {
    img.dataset.seq = String(picture.seq);
    img.src = `api/board/${encodeURIComponent(name)}/picture.png?seq=${picture.seq}`;
  }
  return img;
}

function el(tag, attrs, ...children) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attrs || {})) node.setAttribute(key, value);
  for (const child of children) node.append(child);
  return node;
}

function fixed(value, digits) {
  return typeof value === "number" ? value.toFixed(digits) : "–";
}

function boardCard(name, board) {
  const online = board.online === true;
  const state = online ? ((board.state || {}).state || "?") : "LOST";
  const card = el("section", { class: "board", "data-board": name,
                               "data-online": String(online), "data-state": state });
  const badgeClass = !online ? "badge lost"
    : state === "Spraying" ? "badge" : state === "Fault" ? "badge fault" : "badge idle";
  card.append(el("h2", {}, name, el("span", { class: badgeClass }, state)));
  const bars = el("div", { class: "bars", title: "nozzle duty %" });
  for (const duty of ((board.nozzles || {}).duty_pct || [])) {
    bars.append(el("div", { class: "bar", style: `height:${Math.max(0, Math.min(100, duty))}%` }));
  }
  card.append(bars);
  if (board.picture) card.append(pictureOf(name, board.picture));
  const pressure = board.pressure || {};
  const speed = board.speed || {};
  const flow = board.flow || {};
  const tank = board.tank || {};
  card.append(el("div", { class: "figures" },
    el("span", {}, "pressure ", el("b", {}, fixed(pressure.mpa * 10, 1)), " bar"),
    el("span", {}, "speed ", el("b", {}, fixed(speed.m_per_s * 3.6, 1)), " km/h"),
    el("span", {}, "rate ", el("b", {}, fixed(flow.l_per_ha, 0)), " L/ha"),
    el("span", { class: "dose" }, "dose ", el("b", {}, fixed(flow.target_l_per_ha, 0)), " L/ha"),
    el("span", {}, "tank ", el("b", {}, fixed(tank.level_pct, 0)), " %")));
  for (const alarm of ((board.alarms || {}).alarms || [])) {
    card.append(el("div", { class: `alarm ${alarm.severity}` },
      el("b", {}, alarm.name), ": ", alarm.remedy));
  }
  return card;
}

function offsetOf(board) {
  const info = board.info || {};
  return typeof info.first_nozzle_offset_m === "number" ? info.first_nozzle_offset_m : 1e9;
}

function draw(machine) {
  document.getElementById("machine").textContent = `weedspray: ${machine.machine}`;
  const link = document.getElementById("link");
  link.textContent = machine.broker_connected ? "broker connected" : "broker lost";
  link.className = machine.broker_connected ? "badge" : "badge lost";
  const names = Object.keys(machine.boards)
    .sort((a, b) => offsetOf(machine.boards[a]) - offsetOf(machine.boards[b]) || a.localeCompare(b));
  const main = document.getElementById("boards");
  main.replaceChildren(...names.map((name) => boardCard(name, machine.boards[name])));
}

async function poll() {
  try {
    const response = await fetch("api/machine", { cache: "no-store" });
    draw(await response.json());
  } catch (error) {
    const link = document.getElementById("link");
    link.textContent = "cab service unreachable";
    link.className = "badge lost";
  }
  setTimeout(poll, POLL_MS);
}

async function send(command, argument) {
  const message = document.getElementById("message");
  try {
    const response = await fetch("api/command", {
      method: "POST",
      headers: { "Content-Type": "application/json" },
      body: JSON.stringify({ command, ...argument, confirmed: true }),
    });
    const reply = await response.json();
    message.textContent = reply.ok ? `${command} sent to every board` : `${command} refused: ${reply.message}`;
  } catch (error) {
    message.textContent = `${command} not sent: ${error}`;
  }
}

function hideConfirm() {
  document.getElementById("confirm-bar").hidden = true;
  clearTimeout(confirmTimer);
}

document.getElementById("start").addEventListener("click", () => {
  document.getElementById("confirm-bar").hidden = false;
  clearTimeout(confirmTimer);
  confirmTimer = setTimeout(hideConfirm, CONFIRM_MS);
});
document.getElementById("confirm").addEventListener("click", () => {
  hideConfirm();
  send("start");
});
document.getElementById("cancel").addEventListener("click", hideConfirm);
document.getElementById("stop").addEventListener("click", () => {
  hideConfirm();
  send("stop");
});
document.getElementById("dose-form").addEventListener("submit", (event) => {
  event.preventDefault();
  send("rate", { l_per_ha: Number(document.getElementById("dose").value) });
});
poll();
