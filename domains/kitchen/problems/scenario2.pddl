; Scenario 2 (Sec. 5.5): as Scenario 1, but two cups are delivered from table1 to table2, one at a time.
(define (problem scenario2)
  (:domain kitchen)
  (:objects start table1 table2 - location
            cup1 cup2 - cup)
  (:init (robot start) (table table1) (table table2) (on cup1 table1) (on cup2 table1) (handempty))
  (:goal (and (on cup1 table2) (on cup2 table2))))
