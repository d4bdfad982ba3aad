"""Colour-marking (c-marking) agents: Simonin et al., Algorithm 4 and section 4.4.

On top of the marking agent's wavefront, an agent that loads at a resource which is not yet
exhausted colours its way back to the base (RETURN & COLOUR TRAIL), so that others can climb the
trail from the base (SEARCH & CLIMB TRAIL). The agent that exhausts a resource descends the
coloured trail and restores the default colour (RETURN & REMOVE TRAIL). Every step also performs
UPDATE-VALUE, so the potential field keeps converging whatever the agent is doing ("coloured
trails do not change the potential field construction").

Choices the paper leaves open, taken here:

* the resource cell itself is coloured when a trail is created (and cleared when it is removed),
  so that LOADING's test "is the cell coloured (part of a trail)?" means "a trail already leads
  here" and later loaders descend without colouring; the base is never coloured.
  ``colour_source=False`` takes the letter instead ("move to a new neighbouring cell ... colour
  the cell": only cells moved into are coloured), so the source cell is coloured only when
  another source's trail passes through it and nearly every loader recolours its way home,
  which repairs broken trails. Measured (seed 2007): the default gives Tables 1 and 2 within
  15 % (one agent excepted); the letter makes Setup 1 and 2 about a third faster than the paper
  (40 agents: 1504 vs 2263; 1 agent in Setup 2: 1225 vs 1790) but Setup 3 twice as fast as the
  default (50×50: 1407 vs 2859; the paper has 805);
* RETURN & REMOVE TRAIL follows the trail-coloured new neighbour of least value; when no such
  neighbour is left (the trail ends, or was already erased) it finishes as a plain descent;
* an agent that arrives in a resource cell already emptied by another simply goes on searching;
* "different from the previous position" holds at the base too, as written: an agent back from
  a source does not climb again, in its next move, the trail it just came down; it explores one
  step and may meet the trail again. (``forget_at_base=True`` lets it climb straight back, which
  the paper's "agent 9 performs multiple trips" could also describe; it makes 1 to 5 agents
  markedly faster than Tables 1 and 2, 1083 instead of 1790 iterations for one agent in
  Setup 2, while the letter reproduces them.)
* climbing only goes *up*: a coloured new neighbour is climbed only if its value is higher than
  the current cell's. Trails are created by descent, so this is how they are climbed; moving to
  any coloured new neighbour, an agent caught on a fragment of trail left when two trails merged
  and one was removed (or coloured below a remover) can circle on it forever;
* (an addition, on by default, ``remove_dead_ends=False`` gives the letter of Algorithm 4) an
  agent that climbs to the end of a trail and finds no resource there erases the trail as in
  RETURN & REMOVE TRAIL. Trails outlive their resource when a remover passes above an agent still
  colouring lower down, or when removing one of two merged trails cuts the other; with the
  literal algorithm such a stale trail is an attractor that exploring agents keep climbing back
  to, and whole teams end up circling in a pocket beside it (seen in Setup 1 runs).
  ``climb_any=True`` takes the letter ("move to highest-valued such cell", up or not).

One trail colour or one colour per trail (``trail_colours``). The paper gives agents "a
distinctive trail colour", and the remover moves to "a new neighbouring cell that has the same
colour as the trail"; with a single colour (the default, :data:`TRAIL`) two trails that merged
share their cells, and removing one cuts the other below the source it still leads to.
``"per-trail"`` gives each trail its own colour: a cell's colour is the set of trails through it,
one bit each (an int, ``NO_COLOUR`` the empty set), and an agent that creates a trail takes a
fresh bit, ``ident + team * k`` for its k-th trail, so no two agents of a team of ``team`` ever
take the same one. Which trails are a cell's own, those that *end* there, is read off the floor:
the bits of the cell carried by at most one neighbour (a trail passing through has two). Then

* LOADING's "is the cell coloured (part of a trail)" means "a trail ends here": a source only
  passed by another source's trail gets a trail of its own;
* RETURN & REMOVE TRAIL erases only the trails ending where it starts, following and clearing
  their bits; the other trails through the same cells stay whole. The dead-end removal erases
  the trails of the dead end that go no higher (a trail that ends there, or peaks there);
* SEARCH & CLIMB TRAIL climbs a cell of any trail ("neighbouring cells are coloured") from off
  the trails, and keeps to the trails of its cell once on one: two trails side by side would
  otherwise make a ring of coloured cells that a climber allowed to go down as well as up
  (``climb_any``) circles forever (seen in Setup 3, 50×50: 3 runs in 30, all 50 agents caught).

This needs the source cell coloured (``colour_source``). With one colour the bit is
:data:`TRAIL` and every rule above reduces to the single-colour ones, step for step.
"""

from __future__ import annotations

import enum

import numpy as np

from robots.foraging._dice import Dice
from robots.foraging._marking import descend, explore, resource_neighbour, update_value
from robots.foraging._types import NO_COLOUR, TRAIL, Action, Neighbour, Perception, opposite


class Task(enum.IntEnum):
    """The tasks of Algorithm 4 an agent can be in."""

    SEARCH = 0  # SEARCH & CLIMB TRAIL
    RETURN = 1  # RETURN TO BASE (descent; the resource is already on a trail)
    COLOUR = 2  # RETURN & COLOUR TRAIL
    REMOVE = 3  # RETURN & REMOVE TRAIL


#: The trail-colour readings: one colour for every trail, or one colour per trail.
TRAIL_COLOURS = ("single", "per-trail")


def ending(colour: int, neighbours: tuple[Neighbour, ...]) -> int:
    """The trails of ``colour`` (a set of bits) that end on this cell: those carried by at most
    one of its ``neighbours`` (a trail passing through is carried by two)."""
    once = twice = 0
    for n in neighbours:
        c = n.colour & colour
        twice |= once & c
        once |= c
    return colour & ~twice


class CMarkingAgent:
    """A colour-marking foraging agent (Simonin et al., Algorithm 4).

    ``ident`` (0 to ``team - 1``) and ``team`` only serve ``trail_colours="per-trail"``, to
    draw colours no teammate draws.
    """

    def __init__(
        self,
        rng: np.random.Generator,
        q_max: int = 100,
        remove_dead_ends: bool = True,
        forget_at_base: bool = False,
        colour_source: bool = True,
        *,
        trail_colours: str = "single",
        climb_any: bool = False,
        ident: int = 0,
        team: int = 1,
    ) -> None:
        if trail_colours not in TRAIL_COLOURS:
            raise ValueError(f"trail_colours {trail_colours!r}: one of {', '.join(TRAIL_COLOURS)}")
        if trail_colours == "per-trail" and not colour_source:
            raise ValueError("per-trail colours need the source cell coloured (colour_source)")
        if not 0 <= ident < team:
            raise ValueError(f"ident {ident} is not in 0..{team - 1}")
        self._dice = Dice(rng)
        self.q_max = q_max
        #: Erase a trail found to end without a resource (see the module docstring).
        self.remove_dead_ends = remove_dead_ends
        #: Start each search at the base with no "previous position" (see the module docstring).
        self.forget_at_base = forget_at_base
        #: Also colour the resource cell itself when creating a trail (see the module docstring).
        self.colour_source = colour_source
        #: One colour per trail, as bits of the cell's colour (see the module docstring).
        self.per_trail = trail_colours == "per-trail"
        #: Climb any coloured new neighbour, not only a higher one (the letter of Algorithm 4).
        self.climb_any = climb_any
        self.ident, self.team = ident, team
        self._made = 0  # trails created so far (per-trail colours)
        #: The trail bits being coloured (COLOUR) or erased (REMOVE).
        self.trail = TRAIL
        self.task = Task.SEARCH
        self.load = 0
        #: Direction of the previous cell, as seen from the current one (None at start).
        self.came_from: int | None = None

    def step(self, p: Perception) -> Action:
        """One iteration: UPDATE-VALUE, LOADING or unloading where due, then move."""
        value = update_value(p)
        task = self.task
        load = 0
        unload = False
        colour: int | None = None
        loading = task == Task.SEARCH and p.resource > 0
        if loading:
            # LOADING: pick up q_max; the world gives at most what is left.
            load = min(self.q_max, p.resource)
            self.load = load
            if p.resource - load > 0:
                if self._own_trails(p):  # "the cell is coloured (it is part of a trail)"
                    task = Task.RETURN
                else:
                    task = Task.COLOUR
                    self.trail = self._new_colour()
            else:
                task = Task.REMOVE
                # one colour: follow any trail down, even from an uncoloured source cell
                self.trail = self._own_trails(p) if self.per_trail else TRAIL
                self.came_from = None  # "new" cells: the way in is the trail to erase
        elif task != Task.SEARCH and p.at_base:
            unload = True  # at the base: unload and execute SEARCH & CLIMB
            self.load = 0
            task = Task.SEARCH
            if self.forget_at_base:
                self.came_from = None  # a new search: any trail from the base may be climbed
        dice = self._dice
        floor = -1 if self.climb_any else value  # the least value a climb may go to
        if task == Task.SEARCH and self.remove_dead_ends and self._at_dead_end(p, floor):
            dead = self._dead_trails(p, value)
            if dead:
                task = Task.REMOVE
                self.trail = dead
                self.came_from = None  # the way down the trail is the way it came up
        if task == Task.SEARCH:
            move = self._search(p.neighbours, self._keep(p), floor, dice)
        elif task == Task.COLOUR:
            # RETURN & COLOUR TRAIL: "move to ... the least value, colour the cell" — each cell
            # moved into, and the source cell too with colour_source.
            if not loading or self.colour_source:
                colour = p.colour | self.trail
            move = descend(p.neighbours, dice)
        elif task == Task.REMOVE:
            if p.colour & self.trail and (not loading or self.colour_source):
                colour = p.colour & ~self.trail
            move = self._follow_trail_down(p.neighbours, dice)
            if move is None:
                task = Task.RETURN
                move = descend(p.neighbours, dice)
        else:
            move = descend(p.neighbours, dice)
        self.task = task
        self.came_from = None if move is None else opposite(move)
        return Action(move, value, colour, load, unload)

    def _new_colour(self) -> int:
        """The colour of a trail about to be created: :data:`TRAIL`, or a bit of its own."""
        if not self.per_trail:
            return TRAIL
        bit = self.ident + self.team * self._made
        self._made += 1
        return 1 << bit

    def _own_trails(self, p: Perception) -> int:
        """The trails of this cell that a loader or remover here counts as its own: with one
        colour, the trail colour if the cell has it; per trail, the trails ending here."""
        if not self.per_trail:
            return p.colour & TRAIL
        return ending(p.colour, p.neighbours)

    def _dead_trails(self, p: Perception, here: int) -> int:
        """At a dead end, the trails to erase: with one colour, the trail; per trail, those of
        this cell that go no higher (no neighbour above ``here`` carries them). That is the
        top of a trail whose source is gone, and also a peak of a trail drawn while the field
        was still converging (it first rises, then falls to its source), which an agent that
        only climbs cannot pass."""
        if not self.per_trail:
            return TRAIL
        up = 0
        for n in p.neighbours:
            if n.value > here:
                up |= n.colour
        return p.colour & ~up

    def _keep(self, p: Perception) -> int:
        """The trails a climber here keeps to: per trail, those of its cell if it is on one
        (-1, any, off a trail or with one colour)."""
        return p.colour if self.per_trail and p.colour != NO_COLOUR else -1

    def _search(
        self, neighbours: tuple[Neighbour, ...], keep: int, floor: int, dice: Dice
    ) -> int | None:
        """SEARCH & CLIMB TRAIL: resource, else climb to the highest new neighbour coloured
        with one of the trails ``keep`` of value at least ``floor``, else EXPLORATION
        (Algorithm 2)."""
        move = resource_neighbour(neighbours, dice)
        if move is not None:
            return move
        back = self.came_from
        best = floor  # climbing goes up: only coloured cells higher than this one
        ties: list[Neighbour] = []
        for n in neighbours:
            if not n.colour & keep or n.direction == back:
                continue
            if n.value > best:
                best = n.value
                ties = [n]
            elif n.value == best:
                ties.append(n)
        if ties:
            return dice.choice(ties).direction
        return explore(neighbours, dice)

    def _at_dead_end(self, p: Perception, floor: int) -> bool:
        """On a trail cell with no resource here or around and no coloured new neighbour above
        ``floor`` to climb to: the top of a trail that leads nowhere any more."""
        if p.colour == NO_COLOUR or p.at_base or p.resource > 0:
            return False
        back, keep = self.came_from, self._keep(p)
        for n in p.neighbours:
            if n.resource > 0:
                return False
            if n.colour & keep and n.direction != back and n.value > floor:
                return False
        return True

    def _follow_trail_down(self, neighbours: tuple[Neighbour, ...], dice: Dice) -> int | None:
        """RETURN & REMOVE TRAIL: the new neighbour of least value that carries the trail being
        erased (:attr:`trail`), if any.

        Not required to be lower than the current cell: values along a trail keep improving after
        it was drawn, and stopping at the first non-monotone step would leave the rest of the
        trail behind. Erasing as it goes, the agent cannot circle on the trail.
        """
        back, trail = self.came_from, self.trail
        best = -1
        ties: list[Neighbour] = []
        for n in neighbours:
            if not n.colour & trail or n.direction == back or n.value < 0:
                continue
            if best < 0 or n.value < best:
                best = n.value
                ties = [n]
            elif n.value == best:
                ties.append(n)
        return dice.choice(ties).direction if ties else None
