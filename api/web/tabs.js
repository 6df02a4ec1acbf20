// The result tabs (WAI-ARIA tabs): click or arrow keys move between them.

export function wireTabs(onShow) {
  const tabs = [...document.querySelectorAll('[role=tab]')];
  const select = (tab) => {
    for (const other of tabs) {
      const selected = other === tab;
      other.setAttribute("aria-selected", String(selected));
      other.tabIndex = selected ? 0 : -1;
      document.getElementById(other.getAttribute("aria-controls")).hidden = !selected;
    }
    onShow && onShow(tab.id);
  };
  tabs.forEach((tab, i) => {
    tab.addEventListener("click", () => select(tab));
    tab.addEventListener("keydown", (event) => {
      const step = { ArrowRight: 1, ArrowLeft: -1 }[event.key];
      if (event.key === "Home" || event.key === "End" || step) {
        event.preventDefault();
        const enabled = tabs.filter((t) => !t.disabled);
        const at = enabled.indexOf(tab);
        const next = event.key === "Home" ? enabled[0] : event.key === "End" ? enabled.at(-1) : enabled[(at + step + enabled.length) % enabled.length];
        next.focus();
        select(next);
      }
    });
  });
}
