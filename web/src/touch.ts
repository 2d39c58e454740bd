// Flying by touch: one finger drags the view round (as the mouse does under pointer lock),
// two fingers drag to fly (up the screen: forward; sideways: strafe). A tap stays a click,
// which the browser makes of it, so the tools work as with a mouse.

/** What a drag asks for, in CSS pixels moved. */
export interface TouchMoves {
  look(dx: number, dy: number): void;
  fly(forward: number, right: number): void;
}

/** Follows the touches on `el` (which should have `touch-action: none`). */
export function touchControls(el: HTMLElement, moves: TouchMoves): void {
  const touches = new Map<number, { x: number; y: number }>();
  el.addEventListener("pointerdown", (e) => {
    if (e.pointerType === "touch") touches.set(e.pointerId, { x: e.clientX, y: e.clientY });
  });
  el.addEventListener("pointermove", (e) => {
    const last = touches.get(e.pointerId);
    if (e.pointerType !== "touch" || !last) return;
    const [dx, dy] = [e.clientX - last.x, e.clientY - last.y];
    touches.set(e.pointerId, { x: e.clientX, y: e.clientY });
    if (touches.size === 1) moves.look(dx, dy);
    // Each of the two fingers reports its own move: half each makes the pair's mean.
    else if (touches.size === 2) moves.fly(-dy / 2, dx / 2);
  });
  for (const end of ["pointerup", "pointercancel"] as const) el.addEventListener(end, (e) => touches.delete(e.pointerId));
}
