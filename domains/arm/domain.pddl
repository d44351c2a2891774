; Arm control (Sec. 5.5, Fig. 5.13): the arm draws a letter by reaching through its way-points in turn.
(define (domain arm)
  (:requirements :strips :typing)
  (:types waypoint)
  (:predicates
    (at ?p - waypoint)               ; the arm's tip is at way-point p
    (next ?p ?q - waypoint)          ; the letter's stroke runs from p to q
    (reached ?p - waypoint)          ; the tip has passed through p
    (rest ?p - waypoint))            ; the pen rests at p (the end of the letter)

  (:action reach
    :parameters (?from ?to - waypoint)
    :precondition (and (at ?from) (next ?from ?to))
    :effect (and (at ?to) (reached ?to) (not (at ?from)))))
