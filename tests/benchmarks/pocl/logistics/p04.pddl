; One city, three places, two trucks; four packages, two for each truck's round.
(define (problem one-city-two-trucks)
  (:domain logistics)
  (:objects c - city north south - location depot - airport t1 t2 - truck p1 p2 p3 p4 - package)
  (:init (in-city north c) (in-city south c) (in-city depot c)
         (at t1 north) (at t2 south)
         (at p1 north) (at p2 north) (at p3 south) (at p4 south))
  (:goal (and (at p1 depot) (at p2 south) (at p3 depot) (at p4 north))))
