"""Furniture styles: a coherent palette and set of materials for every piece of a
suggestion (:func:`augment.render.furniture.build_furniture` builds in one). Plain data,
light to import: the command line lists the names."""
from __future__ import annotations

from dataclasses import dataclass

# Upholstery weaves (surfaces of :mod:`augment.render.surfaces`) a fabric can take.
WEAVES = ("weave", "linen", "boucle", "velvet", "wool")


@dataclass(frozen=True)
class Style:
    """A coherent look for every piece of a suggestion: the palettes' names it takes from
    (an empty tuple takes all of that palette), the weaves of its fabrics, and how often a
    carcass is wood rather than paint and a seat leather rather than fabric."""

    name: str
    woods: tuple = ()
    paints: tuple = ()
    fabrics: tuple = ()
    leathers: tuple = ()
    metals: tuple = ()
    bedding: tuple = ()
    pots: tuple = ()
    rugs: tuple = ()
    rug_patterns: tuple = ()
    weaves: tuple = WEAVES
    wood_share: float = 0.6
    leather_share: float = 0.2


STYLES = {s.name: s for s in (
    Style("scandinavian", woods=("light oak", "ash", "pine"), paints=("white paint", "grey paint", "sage paint"),
          fabrics=("light grey fabric", "cream fabric", "beige fabric", "blue grey fabric"),
          leathers=("cognac leather",), metals=("black steel", "white steel"),
          bedding=("white linen", "grey linen", "linen"), pots=("white ceramic", "woven basket", "terracotta"),
          rugs=("cream wool", "grey wool", "sand wool", "sage wool"), rug_patterns=("plain", "border", "trellis"),
          weaves=("boucle", "linen", "weave"), wood_share=0.7, leather_share=0.05),
    Style("modern", woods=("walnut",), paints=("white paint", "black paint"),
          fabrics=("light grey fabric", "charcoal fabric"), leathers=("black leather",),
          metals=("brushed steel", "black steel"), bedding=("white linen", "grey linen"),
          pots=("black ceramic", "white ceramic"), rugs=("grey wool", "charcoal wool", "cream wool", "navy wool"),
          rug_patterns=("plain", "border", "stripes"), weaves=("weave", "velvet", "boucle"), wood_share=0.3,
          leather_share=0.25),
    Style("mid_century", woods=("teak", "walnut"), paints=("cream paint", "sage paint"),
          fabrics=("mustard fabric", "bottle green fabric", "terracotta fabric", "olive fabric"),
          leathers=("cognac leather",), metals=("brass",), bedding=("linen", "rust linen", "sage linen"),
          pots=("terracotta", "white ceramic"), rugs=("rust wool", "sand wool", "sage wool", "cream wool"),
          rug_patterns=("kilim", "trellis", "stripes"), weaves=("wool", "weave", "velvet"), wood_share=0.85,
          leather_share=0.3),
    Style("industrial", woods=("oak", "dark walnut"), paints=("black paint", "grey paint"),
          fabrics=("olive fabric", "charcoal fabric"), leathers=("cognac leather", "brown leather"),
          metals=("black steel",), bedding=("grey linen", "linen"), pots=("concrete", "terracotta"),
          rugs=("charcoal wool", "grey wool", "rust wool", "sand wool"), rug_patterns=("kilim", "plain", "stripes"),
          weaves=("wool", "weave", "linen"), wood_share=0.7, leather_share=0.6),
    Style("classic", woods=("dark walnut", "walnut", "teak"), paints=("cream paint", "white paint", "navy paint"),
          fabrics=("beige fabric", "cream fabric", "navy fabric", "dusty pink fabric"), leathers=("brown leather",),
          metals=("brass",), bedding=("white linen", "linen", "blue linen"), pots=("white ceramic", "terracotta"),
          rugs=("navy wool", "rust wool", "cream wool", "blush wool"), rug_patterns=("medallion", "border", "trellis"),
          weaves=("velvet", "linen", "wool"), wood_share=0.65, leather_share=0.25),
)}
