; Three cities, a truck in each, two airplanes; six packages: local deliveries in every city, two flights.
(define (problem three-cities-six-packages)
  (:domain logistics)
  (:objects c1 c2 c3 - city c1-po c2-po c3-po - location c1-ap c2-ap c3-ap - airport
            t1 t2 t3 - truck a1 a2 - airplane p1 p2 p3 p4 p5 p6 - package)
  (:init (in-city c1-po c1) (in-city c1-ap c1) (in-city c2-po c2) (in-city c2-ap c2)
         (in-city c3-po c3) (in-city c3-ap c3)
         (at t1 c1-po) (at t2 c2-po) (at t3 c3-ap) (at a1 c1-ap) (at a2 c3-ap)
         (at p1 c1-po) (at p2 c2-po) (at p3 c3-ap) (at p4 c1-ap) (at p5 c3-ap) (at p6 c2-po))
  (:goal (and (at p1 c1-ap) (at p2 c2-ap) (at p3 c3-po) (at p4 c2-ap) (at p5 c1-ap) (at p6 c2-ap))))
