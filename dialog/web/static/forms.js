// The page's forms: the feature question's folded checkboxes and the study screens (consent, instructions,
// questionnaire, break). Loaded before app.js, whose helpers ($, button, socket, status) they use when called.
"use strict";

function featureTree(rows) {
  // the feature groups in words, folded: the top groups open, every group below them one click away; ticking a
  // group ticks everything under it (its number is the checkbox's value, never shown)
  const box = document.createElement("div");
  box.id = "features";
  const parents = [box];  // parents[d]: where a row of depth d goes
  rows.forEach((row) => {
    const label = document.createElement("label");
    const check = document.createElement("input");
    check.type = "checkbox";
    check.value = row.number;
    check.dataset.number = row.number;
    check.addEventListener("change", () => {  // a group checks or clears everything under it
      box.querySelectorAll("input").forEach((other) => {
        if (other.value.startsWith(row.number + ".")) { other.checked = check.checked; }
      });
    });
    const parent = parents[Math.min(row.depth, parents.length - 1)];
    if (row.group) {  // its box ticks the group; a click on its words opens it
      const group = document.createElement("details");
      group.open = row.depth === 0;
      const summary = document.createElement("summary");
      const words = document.createElement("span");
      words.textContent = ` ${row.label}`;
      check.setAttribute("aria-label", row.label);
      summary.append(check, words);
      group.appendChild(summary);
      parent.appendChild(group);
      parents[row.depth + 1] = group;
      parents.length = row.depth + 2;
    } else {
      label.append(check, ` ${row.label}`);
      parent.appendChild(label);
    }
  });
  return box;
}

function sendFeatures(mode) {
  // the fewest numbers: a checked group stands for everything under it
  const checked = [...document.querySelectorAll("#features input:checked")].map((c) => c.value);
  const numbers = checked.filter((n) => !checked.some((m) => m !== n && n.startsWith(m + ".")));
  if (numbers.length === 0) { $("refused").textContent = "Tick at least one group or feature first."; return; }
  send({type: "features", mode, numbers});
}

// -- study screens: instructions and the questionnaire ------------------------------------------------
function showScreen(screen) {
  const box = $("screen");
  box.replaceChildren();
  box.hidden = false;
  box.dataset.title = screen.title;
  $("ask").hidden = true;
  document.body.classList.add("idle");  // between sessions: no kitchen, no stale picture
  status(screen.title);
  const heading = document.createElement("h2");
  heading.textContent = screen.title;
  box.appendChild(heading);
  (screen.text || "").split("\n").filter((t) => t.trim()).forEach((paragraph) => {
    const p = document.createElement("p");
    p.textContent = paragraph;
    box.appendChild(p);
  });
  const form = document.createElement("form");
  if (screen.choices && screen.choices.length) {  // answered by one of its buttons (the consent)
    const buttons = screen.choices.map((choice) => button(choice, "", () => {
      socket.send(JSON.stringify({type: "screen", screen: screen.id, answers: [], choice}));
      buttons.forEach((b) => { b.disabled = true; });
    }, true));
    form.className = "choices";
    form.append(...buttons);
    box.appendChild(form);
    heading.tabIndex = -1;
    heading.focus();  // no choice is made by a stray Enter
    return;
  }
  (screen.items || []).forEach((item, i) => form.appendChild(questionnaireItem(item, i)));
  const submit = button(screen.button || "Continue", "", () => {
    const answers = (screen.items || []).map((item, i) => {
      if (item.kind === "likert") {
        const chosen = form.querySelector(`input[name="item-${i}"]:checked`);
        return chosen ? chosen.value : "";
      }
      return form.querySelector(`[name="item-${i}"]`).value;
    });
    socket.send(JSON.stringify({type: "screen", screen: screen.id, answers}));
    submit.disabled = true;
  }, true);
  form.appendChild(submit);
  box.appendChild(form);
  submit.focus();
}

function questionnaireItem(item, i) {
  const set = document.createElement("fieldset");
  const legend = document.createElement("legend");
  legend.textContent = item.text;
  set.appendChild(legend);
  if (item.kind === "likert") {
    for (let value = item.low; value <= item.high; value++) {
      const label = document.createElement("label");
      const radio = document.createElement("input");
      radio.type = "radio";
      radio.name = `item-${i}`;
      radio.value = String(value);
      label.append(radio, ` ${value}${value === item.low ? " " + item.low_label : value === item.high ? " " + item.high_label : ""} `);
      set.appendChild(label);
    }
  } else {
    const text = document.createElement("textarea");
    text.name = `item-${i}`;
    text.rows = 2;
    text.maxLength = 1000;
    text.setAttribute("aria-label", item.text);
    set.appendChild(text);
  }
  return set;
}
